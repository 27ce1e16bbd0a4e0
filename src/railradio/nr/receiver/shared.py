"""Every receiver of an epoch from one set of correlations (source eq. 4–9 as
:class:`railradio.nr.receiver.correlator.Correlator` implements them, at its FFT floor).

The receivers of a scenario (the source's, the robust one, the cell search) correlate the
same window spectra with references that share parts: the SSS template is one part, the
PSS + SSS template is the SSS part plus a PSS part that depends on N_ID2 only (source eq. 4:
b is linear in its symbols). So, per epoch and block:

* one IFFT per candidate for the SSS part, shared by every receiver that uses the SSS
  template and by the PSS + SSS receivers, and one IFFT per distinct N_ID2 for the PSS part;
  the PSS + SSS correlation is their sum (equal to the correlator's own IFFT of the summed
  spectrum to float32 rounding);
* the magnitudes and their window statistics (μ, σ, the peak) in the same pass, once per
  template;
* the peak refinement to full-rate lags (source eq. 9) reads the grid's own samples at the
  grid offsets (k0 - 1, k0, k0 + 1) and evaluates only the offsets between them
  band-limitedly (for a grid at F_s/2: the two half-lag offsets), from the window spectra
  and the reference spectrum without storing the cross-spectra;
* the CA-CFAR's peak in one pass over the prefix sums.

Results equal the per-receiver :class:`Correlator` to float32 rounding
(``tests/nr/test_engine.py``); which decisions that rounding changes on paper-scale bursts
is measured by :mod:`railradio.nr.engine.equivalence`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.fft as sfft
from numpy.typing import NDArray

import railradio.nr.receiver.kernels as kernels
from railradio.nr.receiver.config import fft_rows
from railradio.nr.receiver.correlator import BlockCorrelation, Correlator, detection_levels


class _TemplateRows:
    """One template's per-candidate, per-block magnitudes and statistics: ``r`` [C, B, K]
    (float32), ``edge`` [C, B, 2] (magnitudes at lag -1 and K), ``stats`` [C, B, 4] (μ, σ,
    the peak, its lag)."""

    def __init__(self, n_c: int, n_b: int, k: int):
        self.r = np.empty((n_c, n_b, k), dtype=np.float32)
        self.edge = np.empty((n_c, n_b, 2), dtype=np.float32)
        self.stats = np.empty((n_c, n_b, 4))

    def grid(self, c: NDArray[np.int64], b: NDArray[np.int64], lag: NDArray[np.int64]) -> NDArray[np.float64]:
        """|c(lag)| on the lag grid for lags -1 … K (the window and its two neighbours)."""
        k = self.r.shape[2]
        inside = np.clip(lag, 0, k - 1)
        out = self.r[c, b, inside].astype(np.float64)
        out = np.where(lag < 0, self.edge[c, b, 0], out)
        return np.where(lag >= k, self.edge[c, b, 1], out)


class SharedCorrelation:
    """The correlations of several :class:`Correlator` s on one burst, each computed once.

    Parameters
    ----------
    correlators : sequence of Correlator
        The receivers (the first is the reference for the shared settings). They must share
        the correlation rate, the SS-block pattern and count, the lag window, the window
        length and the front end's rate.

    Raises
    ------
    ValueError
        When ``correlators`` is empty or two of them differ in a shared setting, or a
        template is neither ``"pss_sss"`` nor ``"sss"``.
    """

    def __init__(self, correlators: Sequence[Correlator]):
        if not correlators:
            raise ValueError("correlators must name at least one Correlator")
        base = correlators[0]

        def shared(c: Correlator) -> tuple:
            g = c.cfg
            return (g.decimation, g.ssb_pattern, g.n_blocks, g.lags, c.n_win, c.template_decimation)

        for c in correlators:
            if shared(c) != shared(base):
                raise ValueError(
                    "correlators must share decimation, ssb_pattern, n_blocks, the lag window and the front end's rate"
                )
            if c.cfg.template not in ("pss_sss", "sss"):
                raise ValueError(f"template must be 'pss_sss' or 'sss', got {c.cfg.template!r}")
        self.cors = list(correlators)
        self.base = base
        self.n_win, self.lags, self.d = base.n_win, base.cfg.lags, base.cfg.decimation
        h = np.arange(1, self.d) / self.d  # the offsets between grid lags [lags]
        theta = 2 * np.pi * np.outer(h, np.fft.fftfreq(self.n_win, 1.0 / self.n_win)) / self.n_win
        self.cs = np.ascontiguousarray(np.concatenate([np.cos(theta), np.sin(theta)]), dtype=np.float32)  # [2H, N]
        self._parts: dict[tuple[str, int, int], NDArray[np.complex64]] = {}
        self._buf = np.empty((base.cfg.n_blocks, self.n_win), dtype=np.complex64)

    def part(self, name: str, n_id1: int, n_id2: int) -> NDArray[np.complex64]:
        """conj(B) of one template part at the correlation rate, n_win bins (cached): ``"sss"``
        (the cell's SSS, as the correlator's ``sss`` spectrum) or ``"pss"`` (N_ID2's PSS:
        the PSS + SSS reference minus the SSS one, which cancels exactly in float32).

        Parameters
        ----------
        name : str
            ``"sss"`` or ``"pss"``.
        n_id1, n_id2 : int
            The cell's N_ID1 (ignored for ``"pss"``) and N_ID2.

        Returns
        -------
        numpy.ndarray of complex64
            [n_win] conjugate spectrum.
        """
        key = (name, 0 if name == "pss" else int(n_id1), int(n_id2))
        if key not in self._parts:
            b = self.base._template(key[1], key[2], "sss")
            if name == "pss":
                b = self.base._template(key[1], key[2], "pss_sss") - b
            self._parts[key] = np.conj(sfft.fft(b, self.n_win)).astype(np.complex64)
        return self._parts[key]

    def _rows(self, zf, n_id1, n_id2, templates: set[str]) -> dict[str, _TemplateRows]:
        """Magnitudes and window statistics per template over the candidates: the SSS part's
        IFFT per candidate, the PSS part's per distinct N_ID2 (when both templates are asked
        for; otherwise the template's own IFFT per candidate)."""
        n_c, (n_b, _) = len(n_id1), zf.shape
        out = {t: _TemplateRows(n_c, n_b, self.lags) for t in templates}
        buf, k = self._buf[:n_b], self.lags
        split = templates == {"pss_sss", "sss"}
        pss = {}
        if split:
            for n2 in sorted({int(v) for v in n_id2}):
                pss[n2] = np.empty_like(buf)
                kernels.load_products(zf, self.part("pss", 0, n2), pss[n2])
                fft_rows(pss[n2], inverse=True, out=pss[n2])
        for c in range(n_c):
            a, b2 = int(n_id1[c]), int(n_id2[c])
            if split or templates == {"sss"}:
                spec = self.part("sss", a, b2)
            else:
                spec = self._full_spectrum("pss_sss", a, b2)
            kernels.load_products(zf, spec, buf)
            fft_rows(buf, inverse=True, out=buf)
            for t, rows in out.items():
                add = split and t == "pss_sss"
                kernels.row_stats(buf, pss[b2] if add else buf, add, k, rows.r[c], rows.edge[c], rows.stats[c])
        return out

    def _full_spectrum(self, template: str, n_id1: int, n_id2: int) -> NDArray[np.complex64]:
        """conj(B) of a whole template (the correlator's own spectrum, cached there)."""
        cor = next(c for c in self.cors if c.cfg.template == template)
        return cor.spectrum(n_id1, n_id2)

    def correlate(
        self,
        zf: NDArray[np.complex64],
        n_id1: NDArray,
        n_id2: NDArray,
        which: Sequence[int] | None = None,
        keep_corr: bool = False,
    ) -> list[BlockCorrelation]:
        """Per-block correlation, detection, AOD and TOA of the candidates for the receivers
        ``which`` (source eq. 4–9), each as its :meth:`Correlator.correlate` gives them.

        Parameters
        ----------
        zf : numpy.ndarray of complex64
            The burst's window spectra (:meth:`Correlator.window_spectra`), [n_blocks, n_win].
        n_id1, n_id2 : numpy.ndarray of int
            The candidates' N_ID1 and N_ID2, [n_cand] each.
        which : sequence of int or None
            Indices of the receivers to run (``None``: all).
        keep_corr : bool
            Keep the first receiver's lag-grid magnitudes in ``corr``.

        Returns
        -------
        list of BlockCorrelation
            One per receiver of ``which``, in that order.
        """
        which = list(range(len(self.cors))) if which is None else list(which)
        zf = np.ascontiguousarray(zf, dtype=np.complex64)
        n_id1, n_id2 = np.asarray(n_id1), np.asarray(n_id2)
        rows = self._rows(zf, n_id1, n_id2, {self.cors[j].cfg.template for j in which})
        cfar: dict[tuple, tuple] = {}
        out = []
        for i, j in enumerate(which):
            cor = self.cors[j]
            t = rows[cor.cfg.template]
            out.append(self._receiver(cor, t, zf, n_id1, n_id2, cfar, keep_corr and i == 0))
        return out

    def _receiver(self, cor, t: _TemplateRows, zf, n_id1, n_id2, cfar: dict, keep_corr: bool) -> BlockCorrelation:
        """One receiver's detections, TOA and AOD from its template's rows."""
        mu, sigma = t.stats[..., 0], t.stats[..., 1]
        eta, k_lo = t.stats[..., 2].copy(), t.stats[..., 3].astype(np.int64)
        eta, k_lo, threshold, pre = self._thresholds(cor, t, mu, sigma, eta, k_lo, cfar)
        spec = np.stack([cor.spectrum(a, b) for a, b in zip(n_id1, n_id2, strict=True)])
        pre_row, pre_vals = self._prescreen(t, zf, spec, eta, k_lo, pre)
        detected = eta > threshold
        n_c = len(n_id1)
        toa, aod, peak = np.full(n_c, np.nan), np.full(n_c, np.nan), np.zeros(n_c)
        for c in range(n_c):
            det = np.flatnonzero(detected[c])
            if det.size == 0:
                continue
            toa[c], peak[c] = self._toa(cor, t, zf, spec, c, det, eta, mu, sigma, k_lo, pre_row, pre_vals)
            top = det[np.argsort(eta[c, det])[::-1][: cor.cfg.n_aod_blocks]]  # source eq. 7
            w = eta[c, top] / eta[c, top].sum()
            aod[c] = float(np.sum(w * cor.beam_angles[top]))
        return BlockCorrelation(
            eta, mu.copy(), sigma.copy(), detected, toa, aod, peak, t.r.copy() if keep_corr else None
        )

    def _thresholds(self, cor, t: _TemplateRows, mu, sigma, eta, k_lo, cfar: dict):
        """The detection rule's threshold and pre-screen level, as ``Correlator._thresholds``
        (the CA-CFAR's peak shared by receivers with the same template and windows)."""
        floor_at = None
        if cor.detector == "cacfar":  # [ours] local noise floor per lag
            key = (cor.cfg.template, cor.ca_window, cor.ca_guard)
            if key not in cfar:
                n_c, n_b, k = t.r.shape
                kb, e, fl = kernels.ca_cfar_peak(t.r.reshape(n_c * n_b, k), cor.ca_window, cor.ca_guard)
                cfar[key] = (kb.reshape(n_c, n_b), e.reshape(n_c, n_b), fl.reshape(n_c, n_b))
            k_lo, e, floor_at = cfar[key]
            eta, k_lo = e.copy(), k_lo.copy()
        return eta, k_lo, *detection_levels(cor, mu, sigma, floor_at)

    def at_offsets(self, t: _TemplateRows, zf, spec, c, b, k0) -> NDArray[np.float64]:
        """|c(k0 + δ)| at the full-rate offsets δ = -1, …, +1 lag (step 1/D) for the
        (candidate, block) pairs ``c``, ``b`` [R]: the grid's own samples at -1, 0, +1 and the
        band-limited values between them. Returns [R, 2D + 1], offsets ascending."""
        h = self.d - 1
        out = np.empty((c.size, 2 * self.d + 1))
        out[:, 0] = t.grid(c, b, k0 - 1)
        out[:, h + 1] = t.grid(c, b, k0)
        out[:, -1] = t.grid(c, b, k0 + 1)
        if h:
            between = kernels.between_lags(zf, spec, b, c, k0, self.base.roots, self.cs)
            out[:, 1 : h + 1] = between[:, :h]
            out[:, h + 2 : 2 * h + 2] = between[:, h:]
        return out

    def _prescreen(self, t, zf, spec, eta, k_lo, pre):
        """η at full-rate lags around the promising peaks, as ``Correlator._prescreen``."""
        n_c, n_b = eta.shape
        cand = eta > pre
        pre_row = np.full((n_c, n_b), -1, dtype=np.int64)
        pre_vals = np.zeros((0, 2 * self.d + 1))
        if self.d > 1 and np.any(cand):
            ci, bi = np.nonzero(cand)
            pre_vals = self.at_offsets(t, zf, spec, ci, bi, k_lo[ci, bi])
            pre_row[ci, bi] = np.arange(ci.size)
            eta[ci, bi] = np.maximum(eta[ci, bi], pre_vals.max(axis=1))
        return pre_row, pre_vals

    def _toa(self, cor, t, zf, spec, c, det, eta, mu, sigma, k_lo, pre_row, pre_vals) -> tuple[float, float]:
        """Candidate ``c``'s TOA [full-rate lags] and peak from its detected blocks (source
        eq. 8–9), as ``Correlator._toa``."""
        g, d = cor.cfg, self.d
        if g.toa_blocks is not None:  # [ours] the most significant detected blocks
            score = (eta[c, det] - mu[c, det]) / sigma[c, det]
            det = det[np.argsort(score)[::-1][: g.toa_blocks]]
        comb = t.r[c, det].sum(axis=0)  # source eq. 8 (decimated lags)
        kc = int(comb.argmax())
        if d > 1:  # eq. 9 at full-rate lags d·kc - d ... d·kc + d
            rows = pre_row[c, det]
            hit = (rows >= 0) & (k_lo[c, det] == kc)
            each = np.empty((det.size, 2 * d + 1))
            each[hit] = pre_vals[rows[hit]]
            if not hit.all():
                miss = det[~hit]
                each[~hit] = self.at_offsets(t, zf, spec, np.full(miss.size, c), miss, np.full(miss.size, kc))
            vals = each.sum(axis=0)
            full = d * kc + np.arange(-d, d + 1)
        else:
            full = np.arange(max(kc - 1, 0), min(kc + 2, g.lags))
            vals = comb[full]
        okl = (full >= 0) & (full < g.lags_full)
        vals, full = vals[okl], full[okl]
        j = int(vals.argmax())
        delta = float(full[j])
        if g.subsample and 0 < j < len(full) - 1:
            y0, y1, y2 = vals[j - 1], vals[j], vals[j + 1]
            den = y0 - 2 * y1 + y2
            if den < 0:
                delta += 0.5 * (y0 - y2) / den
        return delta, float(vals[j])
