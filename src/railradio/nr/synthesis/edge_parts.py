"""The band's edges (:mod:`railradio.nr.synthesis.band_edges`) as unit parts: each link's
edges of its SS-block overlay and of its data, with unit amplitude, from which any amplitude
variant's edges are a weighted sum (the counterpart of :mod:`railradio.nr.synthesis.parts`).

An edge at a symbol's start is the previous symbol's value there minus this symbol's
(:meth:`railradio.nr.synthesis.edge_tables.ChebyshevEdges._link_fast`): its two terms are kept
apart (``cur``, weighted with symbol s's amplitude; ``prev``, with s - 1's), and so are the
taps' gain switches (on the previous symbol's copies) and the burst's end (on the symbol each
copy holds there). The study's path only: exact spill, geometry held over the burst, every
symbol start on the front end's grid.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from railradio.nr.channel.link import Links
from railradio.nr.synthesis.band_edges import SpectralBandEdges
from railradio.nr.synthesis.edge_math import _ceil_samples, _los_phasor
from railradio.nr.waveform.numerology import SAMPLE_RATE_HZ, period_length


class LinkEdges(NamedTuple):
    """One link's edge parts: ``cur``, ``prev`` [2, S, W, J] (part, symbol, grid sample after
    the symbol's start from ``lo``, Chebyshev node), ``base`` [S] each symbol's start on the
    front end's grid, ``lo``, and the burst's end: ``end_sym`` [E] the symbols held there and
    ``end_val`` [2, E, J] their values."""

    r: int
    cur: NDArray[np.complex128]
    prev: NDArray[np.complex128]
    base: NDArray[np.int64]
    lo: int
    end_sym: NDArray[np.int64]
    end_val: NDArray[np.complex128]


class EdgeParts(SpectralBandEdges):
    """:class:`SpectralBandEdges` whose links' edges come as unit parts (:meth:`parts`) and
    are summed per variant (:meth:`weigh`).

    Parameters
    ----------
    See :class:`railradio.nr.synthesis.band_edges.BandEdges`; ``syn`` must be a synthesizer
    with the exact spill whose ``data_beam`` is not ``"none"`` (the data part needs the pool).

    Raises
    ------
    ValueError
        As :class:`BandEdges`, or when ``syn`` has no exact spill or zeroes its pool.
    """

    def __init__(self, syn, pool, d_fe, **kwargs):
        super().__init__(syn, pool, d_fe, **kwargs)
        if not syn.exact_spill or syn.data_beam == "none":
            raise ValueError("syn must have the exact spill and a data pool (data_beam not 'none')")

    def parts(
        self,
        links: Links,
        draws: list[dict],
        t0_s: float = 0.0,
        d2d_m: NDArray | None = None,
        gains: dict | None = None,
    ) -> tuple[list[LinkEdges], int]:
        """Every link's edge parts and the burst's length at the full rate.

        Parameters
        ----------
        links, draws, t0_s, d2d_m, gains
            As :meth:`railradio.nr.synthesis.band_edges.BandEdges.__call__` (no ``serving``:
            the variants' amplitudes hold it; no ``motion``).

        Returns
        -------
        tuple
            (list of :class:`LinkEdges`, m_full).

        Raises
        ------
        ValueError
            When the burst's length at F_s is not a multiple of D_fe, or a symbol start is
            not on the front end's grid.
        """
        syn = self.syn
        num, prof = syn.cfg.num, syn.profile
        n, fs = num.n_fft, num.sample_rate_hz
        sp = syn.span(float(np.max(links.tau_s)) if links.n else 0.0)
        total = int(sp["total"])
        m_full = total * self.d_s
        if m_full % self.d_fe:
            raise ValueError(f"the burst's {m_full} full-rate samples are not a multiple of d_fe = {self.d_fe}")
        if np.any((self.d_s * sp["starts"]) % self.d_fe):
            raise ValueError("every symbol start must be on the front end's grid")
        t_sym = (num.symbol_start(sp["symbols"]) + sp["cps"] + n / 2) / fs + t0_s
        full = np.ones(links.n, dtype=bool) if d2d_m is None else np.asarray(d2d_m) <= syn.full_channel_range_m
        amp_l = np.sqrt(prof.powers / syn.n_sinusoids)
        n_cs = np.ceil(links.tau_s * fs - 1e-9).astype(np.int64)
        t_firsts = (num.symbol_start(sp["s_min"]) + n_cs) / fs + t0_s
        out = []
        for r in range(links.n):
            if n_cs[r] >= total:
                continue
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
            cell = self._cell(links.n_id1[r], links.n_id2[r])
            out.append(self._link_parts(r, draws[r]["pool_idx"], cell, tap, sp, m_full, **link))
        return out, m_full

    def _part_rows(self, shifts, pool_idx, cell, part: int) -> NDArray:
        """:meth:`_symbol_rows` of one part: the overlay alone (0) or the data under it (1)."""
        if part == 0:
            idle = np.full(pool_idx.size, self.syn.idle_row, dtype=np.int64)
            return self._symbol_rows(shifts, idle, cell)  # the idle row is zero: the overlay alone
        return np.take(self._tables(shifts), pool_idx + (cell[0] + 1) * self.pool_all.shape[0], axis=0)

    def _link_parts(self, r, pool_idx, cell, gains, sp, m_full, n_c, tau0_s, w_rad_s, t_first_s, phase0_rad):
        """One link's edge parts (``_link_fast`` with unit amplitude, its terms kept apart)."""
        d, fs, n = self.d_s, SAMPLE_RATE_HZ, self.syn.cfg.num.n_fft
        starts, cps = sp["starts"], sp["cps"]
        n_s = starts.size
        origin0 = d * n_c
        half, n_nodes = self.d_fe // 2, self.x_nodes.size
        base = d * starts // self.d_fe
        prof = self.syn.profile
        nc_full = int(_ceil_samples(tau0_s))
        kern0 = self.kernels(w_rad_s / fs, self.w_points, self.points_band).transpose(0, 2, 1)  # [D_s, R, J]

        def los(p):
            return _los_phasor(p, w_rad_s, t_first_s, origin0, phase0_rad)

        cp_vals = tuple(int(d * c) for c in np.unique(cps))
        tap_shift = np.round(prof.delays_s * fs).astype(np.int64) if gains is not None else np.zeros(0, np.int64)
        shifts = tuple(sorted({0, *cp_vals, *(int(t) for t in tap_shift)}))
        delays, gains_c, basis = self._copies(gains, n_s)
        c = _ceil_samples(tau0_s + delays)
        rho = (c + half) % self.d_fe - half
        kern = self._point_kernels(kern0, c % d, c - (tau0_s + delays) * fs, rho)  # [C, R, J]
        k2 = kern.transpose(1, 0, 2).reshape(kern.shape[1], -1)
        first = c[None, :] + d * starts[:, None]  # [S, C]
        turn = np.exp(1j * w_rad_s * c / fs)
        mult = (gains_c * (los(d * starts)[:, None] * turn) * (first < m_full)).astype(np.complex64)[:, :, None]
        off = (c - rho) // self.d_fe
        nc_off = (nc_full - ((nc_full + half) % self.d_fe - half)) // self.d_fe
        lo = min(int(off.min()), nc_off)
        width = max(int(off.max()), nc_off) - lo + 1
        one_hot = np.zeros((c.size, width), np.complex64)
        one_hot[np.arange(c.size), off - lo] = 1
        cur = np.empty((2, n_s, width, n_nodes), np.complex128)
        prev = np.zeros_like(cur)
        ends = []
        for part in (0, 1):
            rows = self._part_rows(shifts, pool_idx, cell, part)  # [S, n_shift, R]
            now = rows[:, shifts.index(cp_vals[0])].copy()
            for cp in cp_vals[1:]:
                at = d * cps == cp
                now[at] = rows[at, shifts.index(cp)]
            terms = np.empty((2, n_s, now.shape[1]), np.complex128)
            terms[0] = -now / n  # this symbol's value at its start (weight g_s)
            terms[1, 0] = 0
            terms[1, 1:] = rows[:-1, shifts.index(0)] / n  # the previous symbol's (weight g_{s-1})
            vals = (terms.reshape(2 * n_s, -1) @ k2).reshape(2, n_s, c.size, n_nodes) * mult[None]
            local = (vals.transpose(0, 1, 3, 2) @ one_hot).transpose(0, 1, 3, 2)  # [2, S, W, J]
            cur[part], prev[part] = local[0], local[1]
            if gains is not None:  # the taps' gain switches, on the previous symbols' copies
                dg = gains[1:].astype(np.complex128) - gains[:-1]
                b = nc_full + d * starts[1:]
                rho_b = (nc_full + half) % self.d_fe - half
                frac = prof.delays_s * fs - tap_shift
                kb = self._point_kernels(kern0, np.full(frac.size, nc_full % d), (nc_full - tau0_s * fs) - frac, rho_b)
                w = (dg * (-(1.0 / n) * los(b) * (b < m_full))[:, None]).astype(np.complex64)  # [S-1, L]
                spill = np.take(rows[:-1], [shifts.index(int(t)) for t in tap_shift], axis=1) * w[:, :, None]
                prev[part, 1:, nc_off - lo] += spill.reshape(b.size, -1) @ kb.reshape(-1, n_nodes)
            ends.append(self._end_parts(pool_idx, cell, (gains_c, basis), first, sp, m_full, tau0_s, kern0, los, part))
        end_sym = ends[0][0]
        return LinkEdges(r, cur, prev, base, lo, end_sym, np.stack([e[1] for e in ends]))

    def _end_parts(self, pool_idx, cell, copies, first, sp, m_full, tau0_s, kern0, los, part):
        """``_burst_end`` of one part with unit amplitude, per symbol held at the burst's end:
        (symbols [E], values [E, J])."""
        d, fs, n = self.d_s, SAMPLE_RATE_HZ, self.syn.cfg.num.n_fft
        starts, cps = sp["starts"], sp["cps"]
        nc_full = int(_ceil_samples(tau0_s))
        s_end = int(np.flatnonzero(nc_full + d * starts <= m_full - 1)[-1])
        held = (first < m_full).sum(axis=0) - 1
        mtype, vrow, distinct = cell[0], cell[1], cell[2]
        gains_c, basis = copies
        syms = np.unique(held)
        vals = np.zeros((syms.size, self.x_nodes.size), np.complex128)
        for e, sl in enumerate(syms):
            on = held == sl
            if part == 0:
                if mtype[sl] < 0:
                    continue
                src = distinct[vrow[sl]]
            else:
                src = self.pool_all[pool_idx[sl]].astype(np.complex128)
                if mtype[sl] >= 0:
                    src = src * ~self._masks[mtype[sl]]
            y = m_full - tau0_s * fs - d * (starts[sl] + cps[sl])
            row = (1.0 / n) * src * np.exp(1j * self.w_k * y) * (gains_c[s_end, on] @ basis[on])
            vals[e] = (row @ self.psi) @ kern0[0] * los(m_full)
        return syms.astype(np.int64), vals

    def weigh(self, links_edges: list[LinkEdges], m_full: int, w: NDArray[np.float32]) -> NDArray[np.complex64]:
        """One variant's edges as :meth:`SpectralBandEdges.__call__` returns them (their DFT
        on the front end's bins), from the parts and the variant's amplitudes.

        Parameters
        ----------
        links_edges : list of LinkEdges
            The epoch's edge parts (:meth:`parts`).
        m_full : int
            The burst's length at the full rate.
        w : numpy.ndarray of float32
            [R, 2, S] as :func:`railradio.nr.synthesis.parts.weigh` takes it.

        Returns
        -------
        numpy.ndarray of complex64
            [period_length(m_full / D_fe)] the edges' spectrum (m-point order).
        """
        acc = np.zeros((period_length(m_full // self.d_fe), self.x_nodes.size), np.complex128)
        for le in links_edges:
            g = w[le.r].astype(np.float64)  # [2, S]
            gp = np.zeros_like(g)
            gp[:, 1:] = g[:, :-1]
            local = np.einsum("ps,pswj->swj", g, le.cur) + np.einsum("ps,pswj->swj", gp, le.prev)
            acc[(m_full // self.d_fe) % acc.shape[0]] += np.einsum("pe,pej->j", g[:, le.end_sym], le.end_val)
            self._scatter(acc, le.base, le.lo, local)
        return self._spectrum(acc, m_full)
