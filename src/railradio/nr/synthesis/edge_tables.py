"""The band's edges on the fast path (:class:`railradio.nr.synthesis.band_edges.BandEdges`
with the exact spill, no motion, every symbol start on the front end's grid): each edge's
tones interpolated on the Chebyshev points of each tone segment (the band and the far band's
two sides) instead of tone by tone, from tables of the data pool's rows and each cell's
SS-block values delayed by the few shifts the edges need (cached)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from railradio.nr.synthesis.edge_math import _ceil_samples, _los_phasor
from railradio.nr.waveform.numerology import SAMPLE_RATE_HZ


class ChebyshevEdges:
    """The fast path's methods of :class:`railradio.nr.synthesis.band_edges.BandEdges` (a
    mixin: it reads the tables and kernels that class builds — ``syn``, ``pool_all``,
    ``psi``, ``w_k``, ``w_points``, ``points_band``, ``nu_nodes``, ``x_nodes``, ``d_s``,
    ``d_fe``, ``k_far``, ``k_all``, ``_rows``, ``_masks``, ``_mask_types``, :meth:`kernels`
    and :meth:`_copies`)."""

    def _cell(self, n_id1: int, n_id2: int) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray]:
        """A cell's SS-block overlay by symbol: its mask type (-1: none) and its distinct
        values' row (-1: none) per symbol, and the distinct values over every tone [U, K]."""
        syn = self.syn
        key = (int(n_id1), int(n_id2), int(syn._span["n_pre"]))
        cached = self._rows.get(("cell",) + key)
        if cached is not None:
            return cached
        ov_row, _, ov_mask, ov_val = syn.overlay(n_id1, n_id2)
        mtype = np.full(ov_row.size, -1, dtype=np.int64)
        vrow = np.full(ov_row.size, -1, dtype=np.int64)
        values: dict[bytes, int] = {}
        for o in range(ov_mask.shape[0]):
            mb = ov_mask[o].tobytes()
            if mb not in self._mask_types:
                self._mask_types[mb] = len(self._masks)
                self._masks.append(np.r_[ov_mask[o], np.zeros(self.k_far.size, bool)])
            vb = ov_val[o].tobytes()
            values.setdefault(vb, len(values))
            at = ov_row == o
            mtype[at], vrow[at] = self._mask_types[mb], values[vb]
        distinct = np.zeros((len(values), self.k_all.size), np.complex128)
        for o in range(ov_val.shape[0]):
            distinct[values[ov_val[o].tobytes()], : ov_val.shape[1]] = ov_val[o]
        out = (mtype, vrow, distinct, key[:2], np.flatnonzero(vrow >= 0))
        self._rows[("cell",) + key] = out
        return out

    def _tables(self, shifts: tuple[int, ...]) -> NDArray[np.complex64]:
        """The data pool's rows (and the idle one) delayed by each of ``shifts`` full-rate
        samples (× e^{-jω_k shift}), interpolated, once per overlay mask type (none, then each
        type: the masked tones cleared): [(T + 1)·(P + 1), len(shifts), R] (cached)."""
        key = ("pool", shifts, len(self._masks))
        if key not in self._rows:
            out = []
            for sh in shifts:
                src = self.pool_all * np.exp(-1j * self.w_k * sh)
                parts = [src] + [src * ~mask for mask in self._masks]
                out.append(np.concatenate(parts) @ self.psi)
            self._rows[key] = np.ascontiguousarray(np.stack(out, axis=1).astype(np.complex64))
        return self._rows[key]

    def _overlay_tables(self, cell, shifts: tuple[int, ...]) -> NDArray[np.complex64]:
        """A cell's distinct overlay values delayed by each of ``shifts``, interpolated
        [U, len(shifts), R] (cached)."""
        key = ("ov", cell[3], shifts)
        if key not in self._rows:
            ph = np.exp(-1j * np.outer(shifts, self.w_k))
            self._rows[key] = ((cell[2][:, None, :] * ph[None, :, :]) @ self.psi).astype(np.complex64)
        return self._rows[key]

    def _symbol_rows(self, shifts: tuple[int, ...], pool_idx, cell) -> NDArray[np.complex64]:
        """Every symbol's tones (data under its overlay) delayed by each of ``shifts``,
        interpolated [S, len(shifts), R]."""
        mtype, vrow = cell[0], cell[1]
        out = np.take(self._tables(shifts), pool_idx + (mtype + 1) * self.pool_all.shape[0], axis=0)
        ss = cell[4]
        out[ss] += self._overlay_tables(cell, shifts)[vrow[ss]]
        return out

    def _point_kernels(self, base, cls, eps, rho) -> NDArray[np.complex64]:
        """[E, R, n_nodes]: the kernels at the points (:meth:`kernels`, [D_s, R, n_nodes]) for E edges at samples
        P ≡ ``cls[e]`` (mod D_s), times e^{jω ε_e} (the edge's sub-sample offset) and e^{-jν_i ρ_e}
        (its offset from the F_s/D_fe grid)."""
        k = base[np.asarray(cls)]
        k = k * np.exp(1j * np.outer(eps, self.w_points))[:, :, None]
        k *= np.exp(-1j * np.outer(rho, self.nu_nodes))[:, None, :]
        return k.astype(np.complex64)

    def _link_fast(self, acc, pool_idx, g_r, cell, gains, sp, m_full, n_c, tau0_s, w_rad_s, t_first_s, phase0_rad):
        """One link's edges as :meth:`_link` computes them tone by tone, each edge's tones
        interpolated on the segments' Chebyshev points (exact spill, no motion)."""
        d, fs, n = self.d_s, SAMPLE_RATE_HZ, self.syn.cfg.num.n_fft
        starts, cps = sp["starts"], sp["cps"]
        g = g_r.astype(np.float64) / n
        origin0 = d * n_c
        half, n_nodes = self.d_fe // 2, self.x_nodes.size
        base = d * starts // self.d_fe  # each symbol's start on the F_s/D_fe grid
        prof = self.syn.profile
        nc_full = int(_ceil_samples(tau0_s))
        kern0 = self.kernels(w_rad_s / fs, self.w_points, self.points_band).transpose(0, 2, 1)  # [D_s, R, J]

        def los(p):
            return _los_phasor(p, w_rad_s, t_first_s, origin0, phase0_rad)

        # the rows: each symbol's tones at its end (shift 0: the previous symbol's at the next
        # start), at its start (shift D·cp_s), and at the taps' integer delays (their spill)
        cp_vals = tuple(int(d * c) for c in np.unique(cps))
        tap_shift = np.round(prof.delays_s * fs).astype(np.int64) if gains is not None else np.zeros(0, np.int64)
        shifts = tuple(sorted({0, *cp_vals, *(int(t) for t in tap_shift)}))
        rows = self._symbol_rows(shifts, pool_idx, cell)  # [S, n_shift, R]
        cur = rows[:, shifts.index(cp_vals[0])].copy()
        for cp in cp_vals[1:]:
            at = d * cps == cp
            cur[at] = rows[at, shifts.index(cp)]
        prev = rows[:, shifts.index(0)]
        delta = np.empty_like(cur)
        delta[0] = -g[0] * cur[0]
        delta[1:] = g[:-1, None] * prev[:-1] - g[1:, None] * cur[1:]
        # every copy's symbol edges, summed per offset from the symbol starts' grid
        delays, gains_c, basis = self._copies(gains, starts.size)
        c = _ceil_samples(tau0_s + delays)
        rho = (c + half) % self.d_fe - half
        kern = self._point_kernels(kern0, c % d, c - (tau0_s + delays) * fs, rho)  # [C, R, J]
        vals = (delta @ kern.transpose(1, 0, 2).reshape(kern.shape[1], -1)).reshape(starts.size, c.size, n_nodes)
        first = c[None, :] + d * starts[:, None]  # [S, C]
        turn = np.exp(1j * w_rad_s * c / fs)
        vals *= (gains_c * (los(d * starts)[:, None] * turn) * (first < m_full)).astype(np.complex64)[:, :, None]
        # the copies' edges lie a few grid samples after each symbol's start: summed there
        off = (c - rho) // self.d_fe
        nc_off = (nc_full - ((nc_full + half) % self.d_fe - half)) // self.d_fe
        lo = min(int(off.min()), nc_off)
        width = max(int(off.max()), nc_off) - lo + 1
        one_hot = np.zeros((c.size, width), np.complex64)
        one_hot[np.arange(c.size), off - lo] = 1
        local = (vals.transpose(0, 2, 1) @ one_hot).transpose(0, 2, 1)  # [S, width, J]
        self._burst_end(acc, pool_idx, g, cell, (gains_c, basis), first, sp, m_full, tau0_s, kern0, los)
        if gains is None:
            self._scatter(acc, base, lo, local)
            return
        # the taps' gains switching at each slot start, on the previous symbols' delayed copies
        dg = gains[1:].astype(np.complex128) - gains[:-1]
        b = nc_full + d * starts[1:]
        rho_b = (nc_full + half) % self.d_fe - half
        frac = prof.delays_s * fs - tap_shift
        kern = self._point_kernels(kern0, np.full(frac.size, nc_full % d), (nc_full - tau0_s * fs) - frac, rho_b)
        w = (dg * (-g[:-1] * los(b) * (b < m_full))[:, None]).astype(np.complex64)  # [S-1, L]
        # Σ_l w[s, l] (rows[s, shift_l] @ kern[l]): one small product per tap on a view of
        # the rows (no [S-1, L, R] copy of them)
        spill = np.zeros((b.size, n_nodes), np.complex64)
        for l, t in enumerate(tap_shift):
            spill += w[:, l, None] * (rows[:-1, shifts.index(int(t))] @ kern[l])
        local[1:, nc_off - lo] += spill
        self._scatter(acc, base, lo, local)

    def _scatter(self, acc, base, lo: int, local) -> None:
        """Add ``local`` [S, width, J] at grid samples base[s] + lo + 0..width-1 (disjoint):
        through a strided view of ``acc`` over each run of equally spaced symbol starts, by
        index for a run that reaches past the end of ``acc`` (the front end's period; wrapped)."""
        m, width = acc.shape[0], local.shape[1]
        key = ("runs", base.size, int(base[0]), int(base[-1]))
        runs = self._rows.get(key)
        if runs is None:
            step = np.diff(base)
            cut = np.flatnonzero(step[1:] != step[:-1]) + 1  # a run ends where the spacing changes
            edges = np.r_[0, cut + 1, base.size]
            runs = [
                (int(a), int(b), int(step[a]) if b - a > 1 else 0)
                for a, b in zip(edges[:-1], edges[1:], strict=True)
                if b > a
            ]
            self._rows[key] = runs
        row = acc.strides[0]
        for a, b, stride in runs:
            start = int(base[a]) + lo
            if start + stride * (b - a - 1) + width <= m:
                view = np.lib.stride_tricks.as_strided(
                    acc[start:], shape=(b - a, width, acc.shape[1]), strides=(stride * row, row, acc.strides[1])
                )
                view += local[a:b]
            else:
                acc[(base[a:b, None] + lo + np.arange(width)[None, :]) % m] += local[a:b]

    def _burst_end(self, acc, pool_idx, g, cell, copies, first, sp, m_full, tau0_s, kern0, los) -> None:
        """The burst's end at sample M (where the front end's zero padding begins): every
        copy's piece there ends, the tones summed over the copies on the symbol each holds
        there."""
        d, fs = self.d_s, SAMPLE_RATE_HZ
        starts, cps = sp["starts"], sp["cps"]
        nc_full = int(_ceil_samples(tau0_s))
        s_end = int(np.flatnonzero(nc_full + d * starts <= m_full - 1)[-1])  # the slot (its gains)
        held = (first < m_full).sum(axis=0) - 1  # [C] the symbol each copy holds at M - 1
        mtype, vrow, distinct = cell[0], cell[1], cell[2]
        gains_c, basis = copies
        row = np.zeros(self.k_all.size, np.complex128)
        for sl in np.unique(held):
            on = held == sl
            src = self.pool_all[pool_idx[sl]].astype(np.complex128)
            if mtype[sl] >= 0:
                src = src * ~self._masks[mtype[sl]] + distinct[vrow[sl]]
            y = m_full - tau0_s * fs - d * (starts[sl] + cps[sl])  # the tones' phase reference
            row += g[sl] * src * np.exp(1j * self.w_k * y) * (gains_c[s_end, on] @ basis[on])
        acc[(m_full // self.d_fe) % acc.shape[0]] += (row @ self.psi) @ kern0[0] * los(m_full)
