"""What the band synthesis leaves out of the receiver's band: the full band's symbol edges.

The fast path (:class:`railradio.nr.synthesis.synthesizer.Synthesizer`) synthesizes the central
N_FFT/D_s subcarriers at F_s/D_s; the receiver's front end then keeps |f| < F_s/(2 D_fe)
(:func:`railradio.nr.receiver.frontend.project`). The same burst synthesized with every subcarrier
at the full rate F_s (the fast path at D_s = 1) differs inside the front end's band only at
the signal's discontinuities, because TS 38.211's OFDM symbol is a sum of tones in a
rectangular window (§5.3.1), and the fast path holds each tap's gain over a symbol:

* a tone outside the synthesized band (|k| ≥ N_FFT/(2 D_s)) lies outside the front end's
  band; only its windows' edges reach it;
* the synthesized band, sampled at F_s/D_s, folds its edges' spectra at multiples of
  F_s/D_s into the front end's band, which sampling at F_s does not.

A piece of a tone e^{j ω n} (ω = 2π k/N_FFT, plus the LOS Doppler) running from sample s to
e - 1 has the DTFT a(e) e^{-jνe} κ(ω - ν) - a(s) e^{-jνs} κ(ω - ν), with κ(θ) = 1/(e^{jθ} - 1)
the geometric sum's closed form and a(n) the tone's value. So a burst of M samples gets, at
DFT bin ν_q, -e^{-jν_q P} Σ_k J_k K_k(ν_q) from every edge at sample P where the signal jumps
by J_k in tone k, with K_k(ν) = κ(ω_k - ν) for a tone outside the synthesized band and
-Σ_{m=1}^{D_s-1} e^{-j2π m P/D_s} κ(ω_k - ν - 2π m/D_s) for one inside (its aliases, which
the fast path has and the full rate has not). Inside the front end's band every K_k is
smooth: its nearest pole is half a band or more beyond the band's edge. An edge's spectrum
is therefore interpolated from its values at Chebyshev nodes of the band; the values are
added at the edge's sample on the F_s/D_fe grid (the offset from the grid a phase at each
node), and one FFT per node gives the DFT of every edge at once.

The edges of one link, in full-rate samples (:class:`BandEdges`): its symbols' slots begin
at B_s = ⌈τ0 F_s⌉ + D_s·start_s, where every tap's gain switches to the symbol's; tap l's
delayed copy of symbol s begins at A_{s,l} = ⌈(τ0 + τ_l) F_s⌉ + D_s·start_s; the burst ends
at M. With ``exact_spill`` off, or for a link with one non-fading tap, a symbol's whole
channel switches at B_s instead.
"""

from __future__ import annotations

import numpy as np
import scipy.fft as sfft
from numpy.typing import NDArray

import railradio.nr.synthesis.kernels as kernels
from railradio.nr.channel.link import Links
from railradio.nr.synthesis.beams import at_train_mask, symbol_gains
from railradio.nr.synthesis.edge_math import (
    N_NODES,
    N_POINTS,
    _ceil_samples,
    _chebyshev_lagrange,
    _los_phasor,
    _tone_basis,
    kappa,
)
from railradio.nr.synthesis.edge_tables import ChebyshevEdges
from railradio.nr.synthesis.synthesizer import Synthesizer, _LinkGrid
from railradio.nr.waveform.numerology import N_ACTIVE, N_FFT, SAMPLE_RATE_HZ, period_length


class BandEdges(ChebyshevEdges):
    """The full band's burst minus the band synthesis', inside the front end's band.

    Parameters
    ----------
    syn : Synthesizer
        The fast path whose band the correction completes (its ``cfg.decimation`` is D_s).
    pool : numpy.ndarray of complex64
        The data pool over all N_FFT bins [P, N_FFT] (:func:`railradio.nr.waveform.ssb.qpsk_pool`), the
        one ``syn`` was built from.
    d_fe : int
        The front end's decimation D_fe, a multiple of D_s.
    n_nodes : int
        Chebyshev nodes per edge spectrum.

    Raises
    ------
    ValueError
        When ``d_fe`` is not a multiple of D_s, D_s is 1 (nothing left out), or ``n_nodes`` < 2.
    """

    def __init__(
        self,
        syn: Synthesizer,
        pool: NDArray[np.complex64],
        d_fe: int,
        n_nodes: int = N_NODES,
        n_points: tuple[int, int] = N_POINTS,
        exact: bool = False,
    ):
        d_s = syn.cfg.decimation
        if d_s == 1 or d_fe % d_s:
            raise ValueError(f"d_fe must be a multiple of the synthesis decimation {d_s} > 1, got {d_fe!r}")
        if n_nodes < 2:
            raise ValueError(f"n_nodes must be >= 2, got {n_nodes!r}")
        self.syn, self.d_s, self.d_fe, self.exact = syn, d_s, int(d_fe), exact
        n = syn.cfg.num.n_fft
        k_band = syn.k.astype(np.int64)  # the fast path's bins, in its FFT order
        k_far = np.r_[np.arange(-N_ACTIVE // 2, -n // 2), np.arange(n // 2, N_ACTIVE // 2)]
        self.k_far = k_far
        self.k_all = np.r_[k_band, k_far]
        self.w_k = 2 * np.pi * self.k_all / N_FFT  # [rad/full-rate sample]
        self.is_band = np.r_[np.ones(k_band.size, bool), np.zeros(k_far.size, bool)]
        far = np.asarray(pool)[:, k_far % N_FFT]
        if syn.data_beam == "none":
            far = np.zeros_like(far)
        self.pool_far = np.vstack([far, np.zeros((1, k_far.size), far.dtype)]).astype(np.complex64)  # + idle row
        self.x_nodes = _chebyshev_lagrange(np.zeros(0), n_nodes)[0]
        self.nu_nodes = self.x_nodes * np.pi / self.d_fe  # [rad/full-rate sample]
        self.pool_all = np.concatenate([syn.pool_band, self.pool_far], axis=1)  # [P + 1, K], idle row last
        self.psi, self.k_points = _tone_basis(self.k_all, n, n_points)
        self.w_points = 2 * np.pi * self.k_points / N_FFT
        self.points_band = np.arange(self.k_points.size) < n_points[0]
        self._rows: dict = {}
        self._weights: NDArray | None = None
        self._mask_types: dict[bytes, int] = {}
        self._masks: list[NDArray[np.bool_]] = []
        f_k = self.k_all * (SAMPLE_RATE_HZ / N_FFT)
        self.basis_all = np.exp(-2j * np.pi * np.outer(syn.profile.delays_s, f_k))  # [L, K]
        self.f_k_far = k_far * (SAMPLE_RATE_HZ / N_FFT)

    def kernels(self, w_d: float, w_k: NDArray | None = None, band: NDArray | None = None) -> NDArray:
        """K_k(ν_i) at the nodes, for an edge at a sample P ≡ c (mod D_s), c = 0..D_s-1, of a
        link whose tones are shifted by the LOS Doppler ``w_d`` [rad/full-rate sample]:
        [D_s, n_nodes, K] (``w_k``, ``band``: other tones [rad/full-rate sample] and whether
        each is in the synthesized band; default every tone).

        Parameters
        ----------
        w_d : float
            LOS Doppler [rad/full-rate sample].
        w_k : numpy.ndarray or None
            Tones [rad/full-rate sample] (default: every tone, :attr:`w_k`).
        band : numpy.ndarray of bool or None
            Whether each tone is in the synthesized band (default :attr:`is_band`).

        Returns
        -------
        numpy.ndarray of complex128
            [D_s, n_nodes, len(w_k)].
        """
        w_k = self.w_k if w_k is None else w_k
        band = self.is_band if band is None else band
        th = w_k[None, :] + w_d - self.nu_nodes[:, None]  # [n_nodes, K]
        out = np.empty((self.d_s,) + th.shape, np.complex128)
        out[:, :, ~band] = kappa(th[:, ~band])[None]
        aliases = np.stack([kappa(th[:, band] - 2 * np.pi * m / self.d_s) for m in range(1, self.d_s)])
        turn = np.exp(-2j * np.pi * np.outer(np.arange(self.d_s), np.arange(1, self.d_s)) / self.d_s)
        out[:, :, band] = -np.einsum("cm,mjk->cjk", turn, aliases)
        return out

    def __call__(
        self,
        links: Links,
        draws: list[dict],
        t0_s: float = 0.0,
        d2d_m: NDArray | None = None,
        serving: NDArray[np.bool_] | None = None,
        motion=None,
        gains: dict | None = None,
    ) -> NDArray[np.complex64]:
        """The full-rate burst minus the fast path's, through the front end (no noise).

        Takes the fast path's arguments (:meth:`Synthesizer.__call__`) and its draws;
        ``project(syn(...)[0], D_fe/D_s) + self(...)`` is ``project(full-rate burst, D_fe)``.

        Parameters
        ----------
        links : Links
            The RRHs in range at the epoch.
        draws : list of dict
            Their draws (:meth:`Synthesizer.draws`).
        t0_s : float
            Time of the burst start [s].
        d2d_m, serving, motion
            As :meth:`Synthesizer.__call__`.
        gains : dict of int to numpy.ndarray, optional
            The taps' gains per link index the synthesizer computed for the same draws
            (:attr:`Synthesizer.kept_gains`); missing links' gains are computed here.

        Returns
        -------
        numpy.ndarray of complex64
            [period_length(total·D_s/D_fe)] samples at F_s/D_fe [√W] (the front end's
            period, :func:`railradio.nr.waveform.numerology.period_length`).

        Raises
        ------
        ValueError
            When the burst's length at F_s is not a multiple of D_fe.
        """
        syn = self.syn
        num, prof = syn.cfg.num, syn.profile
        n, fs = num.n_fft, num.sample_rate_hz
        sp = syn.span(float(np.max(links.tau_s)) if links.n else 0.0)
        total = int(sp["total"])
        m_full = total * self.d_s
        if m_full % self.d_fe:
            raise ValueError(f"the burst's {m_full} full-rate samples are not a multiple of d_fe = {self.d_fe}")
        acc = np.zeros((period_length(m_full // self.d_fe), self.x_nodes.size), np.complex128)
        t_sym = (num.symbol_start(sp["symbols"]) + sp["cps"] + n / 2) / fs + t0_s
        at_train = at_train_mask(syn.data_beam, links, serving)
        g_syms, geo_h = symbol_gains(links, draws, at_train, sp, t_sym, motion, syn.f_k)
        geo_far = None if motion is None else self._far_geometry(links, t_sym, motion)
        full = np.ones(links.n, dtype=bool) if d2d_m is None else np.asarray(d2d_m) <= syn.full_channel_range_m
        amp_l = np.sqrt(prof.powers / syn.n_sinusoids)
        n_cs = np.ceil(links.tau_s * fs - 1e-9).astype(np.int64)
        frac = links.tau_s * fs - n_cs
        ramps = np.exp(-2j * np.pi * np.outer(frac + sp["cp0"], syn.k) / n).astype(np.complex64)
        t_firsts = (num.symbol_start(sp["s_min"]) + n_cs) / fs + t0_s
        u = np.empty((sp["symbols"].size, n), dtype=np.complex64)
        on_grid = not np.any((self.d_s * sp["starts"]) % self.d_fe)
        for r in range(links.n):
            if n_cs[r] >= total:
                continue
            pool_idx, g_r = draws[r]["pool_idx"], g_syms[r]
            if not at_train[r] and syn.data_beam != "none":
                pool_idx = np.where(draws[r]["busy"], pool_idx, syn.idle_row)
            tap = None
            if full[r] and prof.powers.size:
                tap = gains.get(r) if gains is not None else None
                tap = syn._tap_gains(links, r, draws[r], amp_l, t_sym)[0] if tap is None else tap
            link = dict(
                n_c=int(n_cs[r]),
                tau0_s=float(links.tau_s[r]),
                w_rad_s=2 * np.pi * float(links.f_los_hz[r]),
                t_first_s=float(t_firsts[r]),
                phase0_rad=float(links.phase0[r]),
            )
            if not self.exact and on_grid and motion is None and (tap is None or syn.exact_spill):
                cell = self._cell(links.n_id1[r], links.n_id2[r])
                self._link_fast(acc, pool_idx, g_r, cell, tap, sp, m_full, **link)
                continue
            ov = syn.overlay(links.n_id1[r], links.n_id2[r])
            grid = _LinkGrid(pool_idx, ov, ramps[r], g_r, sp["long_of"], sp["long_ramp"])
            geo = None if geo_h is None else geo_h[r]
            syn._fill_grid(u, grid, np.ones((1, 1), np.complex64) if geo is None else geo, geo is not None)
            tones = self._tones(u, pool_idx, g_r, float(frac[r]), sp, None if geo_far is None else geo_far[r])
            self._link(acc, tones, tap, sp, m_full, **link)
        return self._spectrum(acc, m_full)

    def _far_geometry(self, links: Links, t_sym: NDArray, motion) -> NDArray[np.complex64]:
        """Under ``motion``, the far tones' per-symbol geometry phase (as
        :func:`railradio.nr.synthesis.beams._motion_geometry`'s for the band): complex64 [R, S, K_far]."""
        t_rx = t_sym[None, :] + links.tau_s[:, None]
        d_tau = motion.delay_s(t_rx) - links.tau_s[:, None]
        ph = motion.phase_excess_rad(t_rx)[:, :, None] - 2 * np.pi * d_tau[:, :, None] * self.f_k_far[None, None, :]
        return np.exp(1j * ph).astype(np.complex64)

    def _tones(self, u, pool_idx, g_r, frac, sp, geo_far) -> NDArray[np.complex128]:
        """Every tone's value per symbol at the symbol's first sample of the fast path's
        placement, divided by the IFFT size: the band's from the fast path's spectra ``u``,
        the far tones' from the data pool with the same amplitude and ramps [S, K]."""
        n = self.syn.cfg.num.n_fft
        cp0 = sp["cp0"]
        far = self.pool_far[pool_idx] * g_r[:, None]
        far *= np.exp(-2j * np.pi * (frac + cp0) * self.k_far / n)[None, :]
        lo = sp["long_of"] >= 0
        far[lo] *= np.exp(-2j * np.pi * np.outer(sp["cps"][lo] - cp0, self.k_far) / n)
        if geo_far is not None:
            far *= geo_far
        return np.concatenate([u, far], axis=1).astype(np.complex128) / n

    def _link(self, acc, tones, gains, sp, m_full, n_c, tau0_s, w_rad_s, t_first_s, phase0_rad) -> None:
        """Add one link's edges to ``acc`` (see the module's description)."""
        d, fs = self.d_s, SAMPLE_RATE_HZ
        n = self.syn.cfg.num.n_fft
        origin0 = d * n_c  # full-rate sample of the fast path's first placed sample

        def los(p):
            return _los_phasor(p, w_rad_s, t_first_s, origin0, phase0_rad)

        kern = self.kernels(w_rad_s / fs)  # [D_s, n_nodes, K]
        starts, cps = sp["starts"], sp["cps"]
        cp_turn = np.exp(2j * np.pi * np.outer(cps, self.k_all) / n)
        nc_full = int(_ceil_samples(tau0_s))
        b = nc_full + d * starts  # slot starts
        s_end = int(np.flatnonzero(b <= m_full - 1)[-1])  # the slot holding the burst's last sample
        if gains is None or not self.syn.exact_spill:  # one channel per symbol, switching at b
            x = tones
            if gains is not None:
                x = tones * (gains.astype(np.complex128) @ self.basis_all + np.sqrt(self.syn.profile.los_power))
            self._copy(acc, x, cp_turn, b, nc_full, 0.0, np.ones(x.shape[0]), kern, los, m_full, s_end, origin0)
            return
        # the taps' gains switch at every slot start, on the previous symbol's copies
        dh = (gains[1:].astype(np.complex128) - gains[:-1]) @ self.basis_all
        jump = (tones[:-1] * cp_turn[:-1]) * dh * np.exp(1j * self.w_k * (nc_full - origin0))[None, :]
        self._add(acc, b[1:], -(jump @ kern[nc_full % d].T) * los(b[1:])[:, None], m_full)
        # each tap's copy of every symbol begins at its own delayed sample
        delays, g, _ = self._copies(gains, starts.size)
        for p, tau_l in enumerate(delays):
            c = int(_ceil_samples(tau0_s + tau_l))
            self._copy(acc, tones, cp_turn, c + d * starts, c, tau_l * fs, g[:, p], kern, los, m_full, s_end, origin0)

    def _copy(self, acc, x, cp_turn, first, c, delay, g, kern, los, m_full, s_end, origin0) -> None:
        """Add the edges of one copy of the symbols ``x`` [S, K] (tone values at the fast
        path's placement), delayed by ``delay`` full-rate samples, symbol s beginning at
        sample ``first[s]`` = c + D_s·start_s with the gain ``g[s]``; the piece holding the
        burst's last sample ends there. The copy's gain switches are not its own (they are
        the slot starts'). ``kern``: :meth:`kernels` [D_s, n_nodes, K]."""
        d = self.d_s
        starts = (first - c) // d
        ph = np.exp(1j * self.w_k * (c - origin0 - delay))
        delta = np.empty_like(x)
        delta[0] = -x[0]
        delta[1:] = x[:-1] * cp_turn[:-1] - x[1:]  # previous symbol's value minus this one's, at its start
        vals = ((delta * ph[None, :]) @ kern[c % d].T) * (g * los(first))[:, None]
        self._add(acc, first, vals, m_full)
        # the burst's end: the piece covering sample M - 1 (this copy's symbol there)
        s_last = int(np.flatnonzero(first <= m_full - 1)[-1]) if first[0] <= m_full - 1 else -1
        if s_last < 0:
            return
        end = x[s_last] * np.exp(1j * self.w_k * (m_full - origin0 - d * starts[s_last] - delay))
        self._add(acc, np.array([m_full]), ((end @ kern[0].T) * g[s_end] * los(m_full))[None, :], m_full, end=True)

    def _add(self, acc, pos, vals, m_full, end: bool = False) -> None:
        """Add edge values at the nodes ``vals`` [E, n_nodes] at full-rate samples ``pos`` [E]
        (those inside the burst; ``end``: the burst's end ``m_full``, where the front end's
        zero padding begins) to the accumulator on the F_s/D_fe grid (the front end's period,
        :func:`railradio.nr.waveform.numerology.period_length`), the offset from the grid a phase
        at each node."""
        pos = np.asarray(pos)
        keep = pos <= m_full if end else pos < m_full
        pos, vals = pos[keep], vals[keep]
        h = self.d_fe // 2
        rho = (pos + h) % self.d_fe - h
        vals = vals * np.exp(-1j * np.outer(rho, self.nu_nodes))
        np.add.at(acc, ((pos - rho) // self.d_fe) % acc.shape[0], vals)

    def _spectrum(self, acc, m_full) -> NDArray[np.complex64]:
        """The edges' sum through the front end: each node's DFT, the nodes interpolated at
        every bin of the front end's band (barycentric Lagrange), back to time at F_s/D_fe."""
        m = acc.shape[0]
        per_node = sfft.fft(np.ascontiguousarray(acc.T).astype(np.complex64), axis=1, workers=1)  # m-point order
        if self._weights is None or self._weights.shape[1] != m:  # ν_q / (π/D_fe) at each bin
            lag = _chebyshev_lagrange(sfft.fftfreq(m, 1.0 / m) / (m / 2.0), self.x_nodes.size)[1]
            self._weights = np.ascontiguousarray(lag.T).astype(np.complex64)
        per_node *= self._weights
        return (sfft.ifft(per_node.sum(axis=0), workers=1) / self.d_fe).astype(np.complex64)

    def _copies(self, gains, n_sym: int) -> tuple[NDArray[np.float64], NDArray[np.complex128], NDArray]:
        """The delayed copies of a link's symbols: delays [C] (s), gains per symbol [S, C]
        (the taps', the LOS added to a tap at delay 0; no taps: one copy of gain 1) and each
        copy's delay as a phase per tone e^{-jω_k τ F_s} [C, K]."""
        prof = self.syn.profile
        if gains is None:
            return np.zeros(1), np.ones((n_sym, 1), np.complex128), np.ones((1, self.k_all.size))
        delays = np.asarray(prof.delays_s, dtype=np.float64)
        g = gains.astype(np.complex128)
        basis = self.basis_all
        if prof.los_power > 0:
            zero = np.flatnonzero(delays == 0)
            if zero.size:
                g[:, zero[0]] += np.sqrt(prof.los_power)
            else:
                delays = np.r_[delays, 0.0]
                g = np.concatenate([g, np.full((n_sym, 1), np.sqrt(prof.los_power), np.complex128)], axis=1)
                basis = np.vstack([basis, np.ones((1, basis.shape[1]))])
        return delays, g, basis


class SpectralBandEdges(BandEdges):
    """:class:`BandEdges` returning the edges' DFT on the front end's m bins (m-point order,
    the spectrum of what :class:`BandEdges` returns in time) instead of their samples; each
    link's values added around the symbol starts by a compiled loop
    (:func:`railradio.nr.synthesis.kernels.scatter_rows`)."""

    def _scatter(self, acc, base, lo: int, local) -> None:
        kernels.scatter_rows(acc, np.asarray(base, dtype=np.int64), int(lo), np.ascontiguousarray(local))

    def _spectrum(self, acc, m_full) -> NDArray[np.complex64]:
        m = acc.shape[0]
        per_node = sfft.fft(np.ascontiguousarray(acc.T).astype(np.complex64), axis=1, workers=1)
        if self._weights is None or self._weights.shape[1] != m:  # ν_q / (π/D_fe) at each bin
            lag = _chebyshev_lagrange(sfft.fftfreq(m, 1.0 / m) / (m / 2.0), self.x_nodes.size)[1]
            self._weights = np.ascontiguousarray(lag.T).astype(np.complex64)
        per_node *= self._weights
        return (per_node.sum(axis=0) / self.d_fe).astype(np.complex64)
