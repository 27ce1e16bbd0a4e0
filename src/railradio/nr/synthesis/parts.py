"""A burst's unit parts: each link's SS-block overlay and its data, synthesized once with
unit amplitude, from which the band synthesis of any amplitude variant is a weighted sum.

The band synthesis (:class:`railradio.nr.synthesis.synthesizer.Synthesizer`) is linear in
what each RRH sends in each symbol: symbol s of link r is its resource grid (the cell's
SS-block overlay where it writes, the data pool elsewhere) times one amplitude g_{r,s} (the
beam's gain toward the train times the link's amplitude, :func:`railradio.nr.synthesis.beams.symbol_gains`),
through the link's channel. A case or map cell that changes only those amplitudes — the Tx
elements M_T (the beam gains), the data's beam and load (whether a symbol carries data, and on
which beam), the Tx power — has the same channel, the same draws and the same noise. So each
link is synthesized once per part p ∈ {overlay, data} with unit amplitude, and a variant's
burst is

    z = Σ_r Σ_s [g_{r,s} P^ov_{r,s} + g_{r,s} d_{r,s} P^data_{r,s}] + noise,

d_{r,s} ∈ {0, 1} whether symbol s carries data. A symbol's part lies in its own slot of the
burst but for the delayed taps' spill into the next slot's first samples (exact spill,
:class:`railradio.nr.synthesis.spill.Spill`), which is kept apart (``prev``) and weighted with
the symbol it comes from. The weighted sum equals the variant's own synthesis to float32
rounding (``tests/nr/test_variants.py``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

import railradio.nr.synthesis.kernels as kernels
from railradio.nr.channel.link import Links
from railradio.nr.channel.tdl import sos_params
from railradio.nr.receiver.config import fft_rows
from railradio.nr.synthesis.synthesizer import Synthesizer, _LinkGrid

PARTS = ("overlay", "data")
"""The unit parts of a link's burst, in the order of :attr:`LinkParts.own`'s second axis."""


class LinkParts(NamedTuple):
    """One epoch's unit parts at the synthesis rate (see the module's description).

    ``own`` [R, 2, T]: each link's symbols of each part, placed, with the spill of each symbol's
    own copies (complex64); ``prev`` [R, 2, S, J]: the previous symbol's spill into each
    slot's first J samples; ``first`` [R, S + 1]: each symbol's first sample (the last entry:
    the end of the last symbol); ``skip`` [R]: links past the burst's end; ``total`` T and
    ``s_min`` as :meth:`Synthesizer.__call__`; ``noise`` [T] the AWGN (complex64)."""

    own: NDArray[np.complex64]
    prev: NDArray[np.complex64]
    first: NDArray[np.int64]
    skip: NDArray[np.bool_]
    total: int
    s_min: int
    noise: NDArray[np.complex64]


class PartsSynthesizer(Synthesizer):
    """:class:`Synthesizer` that returns a burst's unit parts (:meth:`parts`) instead of the
    burst, for the study's path: exact spill, geometry held over the burst (no ``motion``).

    Parameters
    ----------
    See :class:`Synthesizer`; ``data_beam`` and ``load`` do not matter here (the variants
    weigh the data part), but ``data_beam`` must not be ``"none"`` (its pool is zeroed).

    Raises
    ------
    ValueError
        As :class:`Synthesizer`, or when ``exact_spill`` is off or ``data_beam`` is ``"none"``.
    """

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if not self.exact_spill:
            raise ValueError("exact_spill must be on: the parts keep each symbol's spill apart")
        if self.data_beam == "none":
            raise ValueError("data_beam must not be 'none': the data part needs the pool")
        self._j = int(self.spill.spill_reach.max(initial=0))

    def draws(self, links: Links, rng: np.random.Generator) -> list[dict]:
        """:meth:`Synthesizer.draws` (the same stream), each link's uniform draw per symbol
        behind ``busy`` kept as ``busy_u`` [S] (a variant's load ℓ: busy = busy_u < ℓ).

        Parameters
        ----------
        links : Links
            The R links in range.
        rng : numpy.random.Generator
            The epoch's generator.

        Returns
        -------
        list of dict
            As :meth:`Synthesizer.draws`, with ``busy_u``.
        """
        sp = self.span(float(np.max(links.tau_s)) if links.n else 0.0)
        slot = sp["slot"]
        n_slots = int(slot.max()) + 1
        out = []
        for _ in range(links.n):
            idx = rng.integers(0, self.idle_row, size=sp["symbols"].size)
            alpha, phi = sos_params(rng, self.profile.powers.size, self.n_sinusoids)
            out.append({"pool_idx": idx, "alpha": alpha, "phi": phi})
        for d in out:
            d["data_beam"] = rng.integers(0, self.cfg.n_blocks, size=n_slots)[slot]
            d["busy_u"] = rng.random(n_slots)[slot]
            d["busy"] = d["busy_u"] < self.load
        return out

    def parts(
        self,
        links: Links,
        rng: np.random.Generator,
        draws: list[dict],
        t0_s: float = 0.0,
        d2d_m: NDArray | None = None,
        noise: bool = True,
    ) -> LinkParts:
        """The unit parts of every link and the AWGN, drawn from ``rng`` after ``draws`` as
        :meth:`Synthesizer.__call__` draws it.

        Parameters
        ----------
        links : Links
            The RRHs in range at the epoch (their delays, Doppler and phases; the amplitudes
            are the variants').
        rng : numpy.random.Generator
            The epoch's generator, after ``draws``.
        draws : list of dict
            The links' draws (:meth:`Synthesizer.draws`).
        t0_s : float
            Time of the burst start, s.
        d2d_m : numpy.ndarray or None
            [links] 2-D train–RRH distances, m (``full_channel_range_m``).
        noise : bool
            Draw the receiver's AWGN.

        Returns
        -------
        LinkParts
            The parts, the symbols' first samples and the noise.
        """
        num, prof = self.cfg.num, self.profile
        n, fs = num.n_fft, num.sample_rate_hz
        sp = self.span(float(np.max(links.tau_s)) if links.n else 0.0)
        symbols, total, starts, cps = sp["symbols"], int(sp["total"]), sp["starts"], sp["cps"]
        n_s = symbols.size
        t_sym = (num.symbol_start(symbols) + cps + n / 2) / fs + t0_s
        full = np.ones(links.n, dtype=bool) if d2d_m is None else np.asarray(d2d_m) <= self.full_channel_range_m
        own = np.zeros((links.n, 2, total), dtype=np.complex64)
        prev = np.zeros((links.n, 2, n_s, self._j), dtype=np.complex64)
        amp_l = np.sqrt(prof.powers / self.n_sinusoids)
        n_cs = np.ceil(links.tau_s * fs - 1e-9).astype(np.int64)
        frac = links.tau_s * fs - n_cs
        ramps = np.exp(-2j * np.pi * np.outer(frac + sp["cp0"], self.k) / n).astype(np.complex64)
        t_firsts = (num.symbol_start(sp["s_min"]) + n_cs) / fs + t0_s
        first = n_cs[:, None] + np.r_[starts, starts[-1] + n + cps[-1]][None, :]
        ss_rows = np.flatnonzero(sp["block_of"] >= 0)
        unit = np.ones(n_s, dtype=np.float32)
        idle = np.full(n_s, self.idle_row, dtype=np.int64)
        self.kept_gains = {}
        for r in range(links.n):
            n_c = int(n_cs[r])
            if n_c >= total:
                continue
            ov = self.overlay(links.n_id1[r], links.n_id2[r])
            gains = h = None
            if full[r] and prof.powers.size:
                gains, h = self._tap_gains(links, r, draws[r], amp_l, t_sym)
                self.kept_gains[r] = gains
            phasor = (2 * np.pi * links.f_los_hz[r], float(t_firsts[r]), float(links.phase0[r]))
            for p, rows in enumerate((ss_rows, np.arange(n_s))):
                every = rows.size == n_s
                ov_p = ov if p == 0 else ov[:3] + (np.zeros_like(ov[3]),)
                pool_idx = idle if p == 0 else draws[r]["pool_idx"]
                if not every:
                    ov_p = (ov_p[0][rows],) + ov_p[1:]
                grid = _LinkGrid(pool_idx[rows], ov_p, ramps[r], unit[rows], sp["long_of"][rows], sp["long_ramp"])
                x = np.empty((rows.size, n), dtype=np.complex64)
                u = np.empty_like(x) if h is not None else None
                self._fill_link(x, u, grid, h, None, every, rows)
                y = fft_rows(x, inverse=True, out=x)
                kernels.place(own[r, p], y, starts[rows], cps[rows], n_c, *phasor[:2], phasor[2], 1.0 / fs)
                if u is not None:
                    self._spill_parts(own[r, p], prev[r, p], u, rows, gains, n_c, float(links.tau_s[r]), sp, phasor)
        z_noise = np.zeros(total, dtype=np.complex64)
        if noise:
            var = links.noise_psd_w_hz * fs * links.n_chains
            z_noise = np.float32(np.sqrt(var / 2)) * rng.standard_normal(2 * total, dtype=np.float32).view(np.complex64)
        return LinkParts(own, prev, first, n_cs >= total, total, int(sp["s_min"]), z_noise)

    def _spill_parts(self, own, prev, u, rows, gains, n_c, tau0_s, sp, phasor) -> None:
        """The spill of :meth:`railradio.nr.synthesis.spill.Spill.add` split by the symbol it
        comes from: Δ_s = u_{s-1} e^{j2π k cp_{s-1}/n} - u_s, its -u_s term added to ``own``
        (weighted with symbol s), its u_{s-1} term to ``prev`` [S, J] (weighted with s - 1)."""
        spill, n_s = self.spill, sp["symbols"].size
        n = self.cfg.num.n_fft
        u_all = np.zeros((n_s, n), dtype=np.complex64)
        u_all[rows] = u
        if "cp_turn" not in sp:  # as Spill.add caches it with the layout
            cps, inv = np.unique(sp["cps"][:-1], return_inverse=True)
            sp["cp_turn"] = np.exp(2j * np.pi * np.outer(cps, spill.k) / n).astype(np.complex64)[inv]
        cur_rows = np.zeros(n_s, dtype=bool)
        cur_rows[rows] = True
        prev_rows = np.r_[False, cur_rows[:-1]]
        at_cur = np.zeros((n_s, spill.spill_at.shape[1]), dtype=np.complex64)
        at_prev = np.zeros_like(at_cur)
        at_cur[cur_rows] = -(u_all[cur_rows] @ spill.spill_at)
        at_prev[prev_rows] = (u_all[:-1][cur_rows[:-1]] * sp["cp_turn"][cur_rows[:-1]]) @ spill.spill_at
        b = np.ceil((tau0_s + spill.delays_s) * spill.fs - 1e-9).astype(np.int64) - n_c
        b = np.clip(b, 0, spill.spill_reach)
        w, t_first, phase0 = phasor
        common = (spill.spill_col_of, b, gains, sp["starts"], n_c, w, t_first, phase0, 1.0 / spill.fs)
        kernels.add_spill(own, at_cur, *common)
        scratch = np.zeros(own.size + prev.shape[1], dtype=np.complex64)
        kernels.add_spill(scratch[: own.size], at_prev, *common)
        idx = n_c + sp["starts"][:, None] + np.arange(prev.shape[1])[None, :]
        prev[...] = scratch[np.minimum(idx, own.size)]


def weigh(parts: LinkParts, w: NDArray[np.float32]) -> NDArray[np.complex64]:
    """The burst of one variant from the parts: Σ_r Σ_p Σ_s w[r, p, s] · part + noise.

    Parameters
    ----------
    parts : LinkParts
        The epoch's unit parts (:meth:`PartsSynthesizer.parts`).
    w : numpy.ndarray of float32
        [R, 2, S] each link's amplitude per part and symbol: g_{r,s} for the overlay and
        g_{r,s}·d_{r,s} for the data (:func:`railradio.nr.synthesis.beams.symbol_gains`, × n).

    Returns
    -------
    numpy.ndarray of complex64
        The burst at the synthesis rate, [T] (as :meth:`Synthesizer.__call__`'s ``z``).

    Raises
    ------
    ValueError
        When ``w`` is not [R, 2, S].
    """
    want = (parts.own.shape[0], 2, parts.prev.shape[2])
    if w.shape != want:
        raise ValueError(f"w must have shape {want}, got {w.shape}")
    z = np.zeros(parts.total, dtype=np.complex64)
    _weigh(z, parts.own, parts.prev, parts.first, parts.skip, np.ascontiguousarray(w, dtype=np.float32))
    z += parts.noise
    return z


@njit(cache=True, nogil=True)
def _weigh(z, own, prev, first, skip, w) -> None:
    """z[m] += Σ_r Σ_p w[r, p, s(m)] own[r, p, m] + Σ_r Σ_p w[r, p, s - 1] prev[r, p, s, j] at
    m = first[r, s] + j (s ≥ 1, j < J); samples past the burst's end dropped."""
    n_r, n_p, n_s, n_j = prev.shape
    total = z.size
    for r in range(n_r):
        if skip[r]:
            continue
        for s in range(n_s):
            lo = first[r, s]
            if lo >= total:
                break
            hi = min(first[r, s + 1], total)
            for p in range(n_p):
                g = w[r, p, s]
                if g == 0:
                    continue
                for m in range(lo, hi):
                    z[m] += g * own[r, p, m]
            if s == 0:
                continue
            for p in range(n_p):
                g = w[r, p, s - 1]
                if g == 0:
                    continue
                for j in range(min(n_j, total - lo)):
                    z[lo + j] += g * prev[r, p, s, j]
