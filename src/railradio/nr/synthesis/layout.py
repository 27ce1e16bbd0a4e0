"""The symbol layout of a received SS burst at the synthesis rate and each cell's SS-block
overlay on its resource grid (TS 38.211 §5.3.1, §7.4.3), shared by the band synthesis
(:class:`railradio.nr.synthesis.synthesizer.Synthesizer`) and its band's edges
(:class:`railradio.nr.synthesis.band_edges.BandEdges`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from railradio.nr.receiver.config import ReceiverConfig
from railradio.nr.waveform.numerology import N_FFT, SYMBOLS_PER_SLOT, Numerology
from railradio.nr.waveform.ssb import burst_grid, reference_waveform


class BurstLayout:
    """The burst's symbols, their cyclic prefixes, starts and SS blocks (:meth:`span`, cached by
    the pre-burst length) and each cell's overlay (:meth:`overlay`, cached per cell).

    Parameters
    ----------
    cfg : ReceiverConfig
        The receiver configuration (its rate F_s/D and SS-block pattern).
    """

    def __init__(self, cfg: ReceiverConfig):
        self.cfg = cfg
        self._overlays: dict = {}
        self._span: dict | None = None

    def span(self, max_tau_s: float) -> dict:
        """Symbol layout covering delays up to ``max_tau_s`` (cached by pre-burst length).

        Parameters
        ----------
        max_tau_s : float
            Largest bulk delay of the links [s].

        Returns
        -------
        dict
            ``symbols`` [S] from ``s_min`` = -``n_pre``; ``cps``, ``starts`` (from the first symbol), ``total``
            [samples at F_s/D]; ``slot``, ``block_of`` (-1: no SS block), ``long_of`` [S]; ``long_ramp``; ``cp0``.
        """
        cfg, num = self.cfg, self.cfg.num
        n = num.n_fft
        num1 = Numerology(1)
        n_pre = int(np.ceil(max_tau_s * num1.sample_rate_hz / (N_FFT + 72))) + 1
        if self._span is not None and self._span["n_pre"] >= n_pre:
            return self._span
        n_pre = max(n_pre, 4)
        last_needed = (
            cfg.block_start_full[-1] + cfg.lags_full + len(reference_waveform(num1, 0, 0, int(cfg.ssb_first[-1])))
        )
        s_end = int(cfg.ssb_first[-1])
        while num1.symbol_start(s_end) < last_needed:
            s_end += 1
        symbols = np.arange(-n_pre, s_end + 1)
        cps = num.cp_length(symbols)
        starts = num.symbol_start(symbols) - num.symbol_start(symbols[0])
        total = int(starts[-1] + n + cps[-1])
        # read-out (kernels.place): symbol s occupies n + cp_s samples read cyclically from
        # its IFFT output y_s (0..n-1 then 0..cp_s-1); the CP and the placement offset are
        # folded into the subcarrier phase ramp
        # SS-block symbol -> block index
        block_of = np.full(symbols.size, -1, dtype=np.int64)
        first_pos = {int(sv): i for i, sv in enumerate(symbols)}
        for b, f in enumerate(cfg.ssb_first):
            for off in range(4):
                if int(f) + off in first_pos:
                    block_of[first_pos[int(f) + off]] = b
        cp0 = int(num.cp_length(1))
        long_rows = np.flatnonzero(cps != cp0)
        long_ramp = np.exp(-2j * np.pi * np.outer(cps[long_rows] - cp0, np.fft.fftfreq(n, 1.0 / n)) / n).astype(
            np.complex64
        )
        long_of = np.full(symbols.size, -1, dtype=np.int64)
        long_of[long_rows] = np.arange(long_rows.size)
        slot = symbols // SYMBOLS_PER_SLOT
        slot = slot - slot[0]  # each symbol's slot, 0-based
        self._span = dict(
            n_pre=n_pre,
            symbols=symbols,
            slot=slot,
            cps=np.ascontiguousarray(cps, dtype=np.int64),
            starts=np.ascontiguousarray(starts, dtype=np.int64),
            total=total,
            cp0=cp0,
            long_of=long_of,
            long_ramp=long_ramp,
            block_of=block_of,
            s_min=int(symbols[0]),
        )
        self._overlays.clear()
        return self._span

    def overlay(self, n_id1: int, n_id2: int) -> tuple[NDArray, ...]:
        """Where and what the cell's SS blocks write over the pool data, compact (cached per
        cell): ``(ov_row [symbols], ov_full, ov_mask, ov_val)`` as :func:`kernels.fill_grid`
        takes them — the overlay row of each symbol (-1: none), whether it covers the whole
        band, and its mask and values. Needs :meth:`span` first.

        Parameters
        ----------
        n_id1, n_id2 : int
            The cell's N_ID^(1) and N_ID^(2).

        Returns
        -------
        tuple of numpy.ndarray
            ov_row [S] int64, ov_full [O] bool, ov_mask [O, n] bool, ov_val [O, n] complex64 (O: the
            rows with an overlay; n: n_fft at F_s/D).
        """
        key = (int(n_id1), int(n_id2))
        if key not in self._overlays:
            sp = self._span
            num = self.cfg.num
            marked, _ = burst_grid(
                num,
                sp["symbols"],
                self.cfg.ssb_first,
                *key,
                np.full((1, N_FFT), np.nan + 0j, dtype=np.complex64),
                np.zeros(sp["symbols"].size, dtype=np.int64),
            )
            mask = ~np.isnan(marked.real) & (sp["block_of"][:, None] >= 0)
            rows = np.flatnonzero(mask.any(axis=1))
            ov_row = np.full(mask.shape[0], -1, dtype=np.int64)
            ov_row[rows] = np.arange(rows.size)
            ov_mask = np.ascontiguousarray(mask[rows])
            ov_val = np.ascontiguousarray(np.where(ov_mask, marked[rows], 0).astype(np.complex64))
            self._overlays[key] = (ov_row, ov_mask.all(axis=1), ov_mask, ov_val)
        return self._overlays[key]
