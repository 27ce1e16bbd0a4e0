"""The source's correlation receiver (source eq. 4–9).

Correlation (:class:`Correlator`): one FFT window per SS block (lags 0..K-1 plus the
reference length), R = IFFT(Z·conj(B)) on the receiver's lag grid for the detection
statistics (μ_i, σ_i over the window), and band-limited evaluation at full-rate integer lags
around the peaks for η_i and the TOA (source eq. 9 is an argmax over full-rate samples). The
lag grid may be finer than the front end's samples (``template_decimation``): the samples
band-limited-interpolated, the template zero-stuffed.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.fft as sfft
from numpy.typing import NDArray

import railradio.nr.receiver.kernels as kernels
from railradio.nr.receiver.config import ReceiverConfig, fft_rows
from railradio.nr.waveform.numerology import SUBCARRIER_SPACING_HZ, Numerology
from railradio.nr.waveform.ssb import reference_waveform


@dataclass
class BlockCorrelation:
    """Per-candidate, per-block correlation statistics of one burst.

    Shapes: [n_cand, n_blocks] unless noted. ``corr`` [n_cand, n_blocks, K_d] is the
    decimated-rate |r̃_i[k]| (kept only when requested).
    """

    eta: NDArray[np.float64]
    mu: NDArray[np.float64]
    sigma: NDArray[np.float64]
    detected: NDArray[np.bool_]
    toa_samples: NDArray[np.float64]  # [n_cand] full-rate lag δ̂ (nan: nothing detected)
    aod_rad: NDArray[np.float64]  # [n_cand] (nan: nothing detected)
    peak_comb: NDArray[np.float64]  # [n_cand] max of the combined correlation
    corr: NDArray[np.float32] | None = None


DETECTORS = ("source", "cfar", "cacfar")
CA_WINDOW_FULL = 512
"""The CA-CFAR's reference lags on each side [full-rate lags, 2.08 µs]: the two sides span
4.2 µs, just under one OFDM symbol (4.46 µs), over which the level of the data interference
stays put (64 lags at F_s/8) [ours]."""
CA_PRESCREEN = 0.8
"""The CFAR detectors evaluate a block's peak at full-rate lags when its value on the lag
grid exceeds this share of the threshold: on the F_s/2 grid a band-limited peak falls at most
1 - sinc(1/8) = 2.5 % between grid lags (0.8 keeps a margin for the floor's own change) [ours]."""
CA_GUARD_FULL = 32
"""Guard lags on each side of the tested lag [full-rate lags, 130 ns]: the correlation's
main lobe (±1 lag at F_s/8) and TDL-D's taps within 1.8 delay spreads (36 ns), which hold all
but 0.5 % of its power (4 lags at F_s/8) [ours]."""


def cfar_threshold(window_s: float, pfa: float, n_sc: int = 127) -> float:
    """t with T sqrt(2π) β_rms t exp(-t²/2) = P_fa (Rice's envelope up-crossing rate), in
    units of the Rayleigh parameter σ_R; β_rms = Δf sqrt((n_sc² - 1)/12) [Hz].

    Parameters
    ----------
    window_s : float
        Duration T of the tested lag window [s].
    pfa : float
        False-alarm probability P_fa per block (over its lag window), in (0, 1).
    n_sc : int
        Subcarriers of the reference (127: PSS, SSS).

    Returns
    -------
    float
        The threshold t [σ_R], the root in [1, 50].

    Raises
    ------
    ValueError
        From :func:`scipy.optimize.brentq` when no root lies in [1, 50].
    """
    from scipy.optimize import brentq

    beta = SUBCARRIER_SPACING_HZ * np.sqrt((n_sc**2 - 1) / 12)
    c = window_s * np.sqrt(2 * np.pi) * beta

    def f(t: float) -> float:
        return np.log(c * t) - t * t / 2 - np.log(pfa)

    return float(brentq(f, 1.0, 50.0))


def detection_levels(cor: Correlator, mu: NDArray, sigma: NDArray, floor_at: NDArray | None) -> tuple[NDArray, NDArray]:
    """The threshold and the pre-screen level of ``cor``'s detection rule per candidate and
    block, from the window's μ and σ and, for ``cacfar``, the local noise floor at the peak
    ``floor_at``: the source's μ + kσ (eq. 6, pre-screen at its own k), ``cfar``'s t·μ/√(π/2),
    or ``cacfar``'s larger of the local floor's CFAR level and μ + kσ (both tests).

    Parameters
    ----------
    cor : Correlator
        The receiver (its ``detector``, ``cfg``, ``cfar_factor`` and ``ca_prescreen``).
    mu, sigma : numpy.ndarray
        The window's mean and standard deviation of |c| [n_cand, n_blocks].
    floor_at : numpy.ndarray or None
        The CA-CFAR's local floor at the peak (``cacfar`` only).

    Returns
    -------
    tuple of numpy.ndarray
        ``(threshold, pre)``.
    """
    g = cor.cfg
    if cor.detector == "cacfar":
        threshold = np.maximum(floor_at * cor.cfar_factor, mu + g.detect_k_sigma * sigma)
        return threshold, threshold * cor.ca_prescreen
    if cor.detector == "cfar":
        threshold = mu * cor.cfar_factor
        return threshold, threshold * cor.ca_prescreen
    return mu + g.detect_k_sigma * sigma, mu + g.prescreen_k_sigma * sigma


class Correlator:
    """The source's correlation receiver for a set of candidate cells (source eq. 4–9).

    Detection rule ``detector``: ``"source"`` η_i > μ_i + kσ_i (source eq. 6, k = 4);
    ``"cacfar"`` [ours] the source's test and a cell-averaging CFAR test (the peak against the
    mean of the ``ca_window`` lags on each side, beyond ``ca_guard``, scaled like ``cfar``):
    robust to the data interference whose level varies across the window; or
    ``"cfar"`` [ours] η_i > t · μ_i / sqrt(π/2): on noise the correlation magnitude is a
    Rayleigh envelope (μ = σ_R sqrt(π/2)) whose expected number of up-crossings of t·σ_R
    over the window T = K/F_s is T sqrt(2π) β_rms t e^{-t²/2} (Rice, 1945), with β_rms the
    RMS bandwidth of the 127-subcarrier reference, Δf sqrt((127² - 1)/12); t solves that
    number = P_fa, the false-alarm probability per block.
    """

    def __init__(
        self,
        cfg: ReceiverConfig,
        detector: str = "source",
        pfa: float = 1e-3,
        ca_window: int | None = None,
        ca_guard: int | None = None,
        template_decimation: int | None = None,
    ):
        """``ca_window``, ``ca_guard``: the CA-CFAR's reference lags on each side and guard
        lags at this correlator's rate (default: :data:`CA_WINDOW_FULL` and
        :data:`CA_GUARD_FULL` full-rate lags). ``template_decimation``: the rate F_s/D_t of
        the receiver's front end when the correlation runs faster than it (the reference
        waveform is built at F_s/D_t and band-limited-interpolated to ``cfg``'s rate: the
        correlation is then the band-limited interpolation of the front end's own).

        Parameters
        ----------
        cfg : ReceiverConfig
            The receiver configuration; its decimation D sets the correlation rate F_s/D (lags).
        detector : str
            ``"source"``, ``"cfar"`` or ``"cacfar"``.
        pfa : float
            False-alarm probability per block of the CFAR tests, in (0, 1).
        ca_window : int or None
            CA-CFAR reference lags on each side (lags at F_s/D).
        ca_guard : int or None
            CA-CFAR guard lags on each side (lags at F_s/D).
        template_decimation : int or None
            D_t, a multiple of D (None: D).

        Raises
        ------
        ValueError
            When ``detector`` is unknown, ``template_decimation`` is not a multiple of D, or
            ``pfa`` is outside (0, 1).
        """
        if detector not in DETECTORS:
            raise ValueError(f"detector must be one of {DETECTORS}, got {detector!r}")
        d = cfg.decimation
        td = d if template_decimation is None else int(template_decimation)
        if td < d or td % d:
            raise ValueError(
                f"template_decimation must be a multiple of the decimation {d}, got {template_decimation!r}"
            )
        self.template_decimation = td
        self.ca_window = CA_WINDOW_FULL // d if ca_window is None else int(ca_window)
        self.ca_guard = CA_GUARD_FULL // d if ca_guard is None else int(ca_guard)
        self.ca_prescreen = CA_PRESCREEN
        if not 0 < pfa < 1:
            raise ValueError(f"pfa must be in (0, 1), got {pfa!r}")
        self.cfg, self.detector, self.pfa = cfg, detector, pfa
        b0 = self._template(0, 0, "pss_sss")
        self.ref_len = len(b0)
        self.n_win = sfft.next_fast_len(cfg.lags + self.ref_len - 1)
        self._spectra: dict[tuple[int, int], NDArray[np.complex64]] = {}
        self.freqs = np.fft.fftfreq(self.n_win, 1.0 / self.n_win)
        # e^{j2π f δ/N} for the full-rate offsets δ = -1 ... +1 (decimated units, step 1/D)
        self.offsets_full = np.arange(-d, d + 1)  # full-rate samples
        self.offsets = self.offsets_full / d
        theta = 2 * np.pi * np.outer(self.offsets[d:], self.freqs) / self.n_win  # δ >= 0: [d + 1, N]
        # [N, 2(d + 1)]: cos θ | sin θ, the right-hand factor of kernels.at_offsets
        self.offset_cs_t = np.ascontiguousarray(np.concatenate([np.cos(theta), np.sin(theta)]).T.astype(np.float32))
        self.roots = np.exp(2j * np.pi * np.arange(self.n_win) / self.n_win).astype(np.complex64)
        self.cfar_factor = cfar_threshold(cfg.lags_full / Numerology(1).sample_rate_hz, pfa) / np.sqrt(np.pi / 2)

    def _template(self, n_id1: int, n_id2: int, template: str) -> NDArray[np.complex64]:
        """The reference waveform b at the correlation rate. Built at the front end's rate
        F_s/D_t and zero-stuffed to this one: on a burst interpolated from the front end's
        samples (:func:`railradio.nr.receiver.frontend.upsample`) the correlation at lag λ is then
        Σ_n b*[n] z(n + λ) with z band-limited-interpolated, exactly the front end's own
        correlation at integer lags and its band-limited interpolation between them."""
        td, d = self.template_decimation, self.cfg.decimation
        b = reference_waveform(Numerology(td), n_id1, n_id2, int(self.cfg.ssb_first[0]), template)
        if td == d:
            return b
        f = td // d
        out = np.zeros((b.size - 1) * f + 1, dtype=np.complex64)
        out[::f] = b
        return out

    def spectrum(self, n_id1: int, n_id2: int) -> NDArray[np.complex64]:
        """conj(B): the conjugate reference spectrum of a cell, n_win bins (cached per cell).

        Parameters
        ----------
        n_id1, n_id2 : int
            The cell's N_ID1 and N_ID2 (PCI = 3 N_ID1 + N_ID2).

        Returns
        -------
        numpy.ndarray of complex64
            conj(FFT) of the ``cfg.template`` reference zero-padded to n_win, [n_win].
        """
        key = (int(n_id1), int(n_id2))
        if key not in self._spectra:
            b = self._template(*key, self.cfg.template)
            self._spectra[key] = np.conj(sfft.fft(b, self.n_win)).astype(np.complex64)
        return self._spectra[key]

    def _at_offsets(
        self, p: NDArray[np.complex64], rows: NDArray[np.int64], k0: NDArray[np.int64]
    ) -> NDArray[np.float64]:
        """|c(k0 + δ)| for δ in ``self.offsets`` from the rows ``rows`` of the cross-spectra
        p [M, N] (band-limited evaluation: c(λ) = (1/N) Σ_f p[f] e^{j2π f λ/N})."""
        return kernels.at_offsets(
            p, np.asarray(k0, dtype=np.int64), self.roots, self.offset_cs_t, np.asarray(rows, dtype=np.int64)
        )

    def window_spectra(self, z: NDArray[np.complex64], s_min: int) -> NDArray[np.complex64]:
        """FFT of the received burst over each SS block's window (v_i ... v_i + N - 1),
        [n_blocks, N]; receivers with the same window length can share it.

        Parameters
        ----------
        z : numpy.ndarray of complex64
            The burst's samples at the correlation rate F_s/D, [n_samples] (taken as zero beyond its end).
        s_min : int
            Symbol index of the burst's first sample.

        Returns
        -------
        numpy.ndarray of complex64
            [n_blocks, n_win] window spectra.
        """
        num = self.cfg.num
        v = num.symbol_start(self.cfg.ssb_first) - num.symbol_start(s_min)  # [B]
        idx = v[:, None] + np.arange(self.n_win)[None, :]
        zw = np.zeros((len(v), self.n_win), dtype=np.complex64)
        ok = idx < z.size
        zw[ok] = z[idx[ok]]
        return fft_rows(zw, out=zw)

    def correlate(
        self,
        z: NDArray[np.complex64],
        s_min: int,
        n_id1: NDArray,
        n_id2: NDArray,
        keep_corr: bool = False,
        zf: NDArray[np.complex64] | None = None,
    ) -> BlockCorrelation:
        """Per-block correlation, detection, AOD and TOA of the candidate cells (source eq. 4–9).

        ``zf``: the burst's :meth:`window_spectra`, when already computed for ``z``.

        Parameters
        ----------
        z : numpy.ndarray of complex64
            The burst's samples at the correlation rate F_s/D, [n_samples].
        s_min : int
            Symbol index of the burst's first sample.
        n_id1, n_id2 : numpy.ndarray of int
            The candidates' N_ID1 and N_ID2, [n_cand] each.
        keep_corr : bool
            Keep the decimated-rate |r̃_i[k]| in ``corr``.
        zf : numpy.ndarray of complex64 or None
            [n_blocks, n_win] window spectra of ``z`` (``None``: computed here).

        Returns
        -------
        BlockCorrelation
            η, μ, σ, detections [n_cand, n_blocks]; TOA [full-rate samples], AOD [rad] and the
            combined peak [n_cand] (NaN TOA/AOD, 0 peak: nothing detected); ``corr``
            [n_cand, n_blocks, K_d] or ``None``.
        """
        cfg = self.cfg
        if zf is None:
            zf = self.window_spectra(z, s_min)  # [B, N]
        n_c = len(n_id1)
        n_b = zf.shape[0]
        bspec = np.stack([self.spectrum(a, b) for a, b in zip(n_id1, n_id2, strict=True)])  # [C, N]
        p = np.empty((n_c, n_b, self.n_win), dtype=np.complex64)
        kernels.cross_spectra(np.ascontiguousarray(zf, dtype=np.complex64), bspec, p)  # [C, B, N]
        p2 = p.reshape(n_c * n_b, self.n_win)  # row c·B + b
        # one candidate at a time: its IFFT and the pass over |r| stay in cache
        r = np.empty((n_c, n_b, cfg.lags), dtype=np.float32)
        mu, sigma, eta = (np.empty((n_c, n_b)) for _ in range(3))
        k_lo = np.empty((n_c, n_b), dtype=np.int64)
        for c in range(n_c):
            xc = fft_rows(p[c], inverse=True)
            r[c], mu[c], sigma[c], eta[c], k_lo[c] = kernels.magnitude_stats(xc, cfg.lags)
        eta, k_lo, threshold, pre = self._thresholds(r, mu, sigma, eta, k_lo)
        pre_row, pre_vals = self._prescreen(p2, eta, k_lo, pre)
        detected = eta > threshold
        toa = np.full(n_c, np.nan)
        aod = np.full(n_c, np.nan)
        peak = np.zeros(n_c)
        for c in range(n_c):
            det = np.flatnonzero(detected[c])
            if det.size == 0:
                continue
            toa[c], peak[c] = self._toa(p2, c, det, r, eta, mu, sigma, k_lo, pre_row, pre_vals)
            det = np.flatnonzero(detected[c])
            top = det[np.argsort(eta[c, det])[::-1][: cfg.n_aod_blocks]]  # source eq. 7
            w = eta[c, top] / eta[c, top].sum()
            aod[c] = float(np.sum(w * self.beam_angles[top]))
        return BlockCorrelation(eta, mu, sigma, detected, toa, aod, peak, r.astype(np.float32) if keep_corr else None)

    def _thresholds(self, r, mu, sigma, eta, k_lo) -> tuple[NDArray, NDArray[np.int64], NDArray, NDArray]:
        """The detection rule's threshold and pre-screen level per candidate and block
        [n_cand, n_blocks], from the lag-grid statistics ``r`` [n_cand, n_blocks, K_d], μ, σ,
        η and the peak lags ``k_lo``. Returns ``(eta, k_lo, threshold, pre)``: the ``cacfar``
        detector's peak is the lag maximizing r/floor, so it replaces η and ``k_lo``."""
        n_c, n_b = mu.shape
        floor_at = None
        if self.detector == "cacfar":  # [ours] local noise floor per lag
            k_lo, eta, floor_at = (
                a.reshape(n_c, n_b)
                for a in kernels.local_mean_argmax(r.reshape(n_c * n_b, self.cfg.lags), self.ca_window, self.ca_guard)
            )
        return eta, k_lo, *detection_levels(self, mu, sigma, floor_at)

    def _prescreen(
        self, p2: NDArray[np.complex64], eta: NDArray[np.float64], k_lo: NDArray[np.int64], pre: NDArray[np.float64]
    ) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
        """η at full-rate lags around the promising peaks (η > ``pre``), in place in ``eta``.
        Returns ``(pre_row, pre_vals)``: each block's row of ``pre_vals`` (-1: none), the
        values at :attr:`offsets` around its peak lag ``k_lo``."""
        n_c, n_b = eta.shape
        cand = eta > pre
        pre_row = np.full((n_c, n_b), -1, dtype=np.int64)  # row of pre_vals, evaluated at k_lo
        pre_vals = np.zeros((0, self.offsets.size))
        if self.cfg.decimation > 1 and np.any(cand):  # η at full-rate lags around promising peaks
            ci, bi = np.nonzero(cand)
            pre_vals = self._at_offsets(p2, ci * n_b + bi, k_lo[ci, bi])
            pre_row[ci, bi] = np.arange(ci.size)
            eta[ci, bi] = np.maximum(eta[ci, bi], pre_vals.max(axis=1))
        return pre_row, pre_vals

    def _toa(
        self,
        p2: NDArray[np.complex64],
        c: int,
        det: NDArray[np.int64],
        r: NDArray[np.float32],
        eta: NDArray[np.float64],
        mu: NDArray[np.float64],
        sigma: NDArray[np.float64],
        k_lo: NDArray[np.int64],
        pre_row: NDArray[np.int64],
        pre_vals: NDArray[np.float64],
    ) -> tuple[float, float]:
        """Candidate ``c``'s TOA δ̂ [full-rate lags] and peak from its detected blocks ``det``
        (source eq. 8–9). Returns ``(delta, peak)``."""
        cfg = self.cfg
        d = cfg.decimation
        n_b = eta.shape[1]
        if cfg.toa_blocks is not None:  # [ours] the most significant detected blocks
            score = (eta[c, det] - mu[c, det]) / sigma[c, det]
            det = det[np.argsort(score)[::-1][: cfg.toa_blocks]]
        comb = r[c, det].sum(axis=0)  # source eq. 8 (decimated lags)
        kc = int(comb.argmax())
        if d > 1:  # eq. 9 at full-rate lags d·kc - d ... d·kc + d
            # blocks whose own peak lag is kc were evaluated there already
            rows = pre_row[c, det]
            hit = (rows >= 0) & (k_lo[c, det] == kc)
            each = np.empty((det.size, self.offsets.size))
            each[hit] = pre_vals[rows[hit]]
            if not hit.all():
                each[~hit] = self._at_offsets(p2, c * n_b + det[~hit], np.full(int((~hit).sum()), kc))
            vals = each.sum(axis=0)
            full = d * kc + self.offsets_full
        else:
            full = np.arange(max(kc - 1, 0), min(kc + 2, cfg.lags))
            vals = comb[full]
        okl = (full >= 0) & (full < cfg.lags_full)
        vals, full = vals[okl], full[okl]
        j = int(vals.argmax())
        delta = float(full[j])
        if cfg.subsample and 0 < j < len(full) - 1:
            y0, y1, y2 = vals[j - 1], vals[j], vals[j + 1]
            den = y0 - 2 * y1 + y2
            if den < 0:
                delta += 0.5 * (y0 - y2) / den
        return delta, float(vals[j])

    @cached_property
    def beam_angles(self) -> NDArray[np.float64]:
        """Direction of each SS block's beam, the AOD it stands for (source eq. 7) [rad]:
        -(k + 1/2) · 180°/n_blocks, [n_blocks].
        """
        k = np.arange(self.cfg.n_blocks)
        return -np.radians((k + 0.5) * 180.0 / self.cfg.n_blocks)
