"""The delayed taps' spill across OFDM symbol boundaries in the band synthesis
(:class:`railradio.nr.synthesis.synthesizer.Synthesizer` with ``exact_spill``): what the cyclic
read-out of each symbol's IFFT leaves out, added exactly."""

from __future__ import annotations

import numpy as np

import railradio.nr.synthesis.kernels as kernels
from railradio.nr.channel.tdl import TdlProfile
from railradio.nr.waveform.numerology import Numerology


class Spill:
    """The spill's tables for one TDL profile at one synthesis rate, and its addition to a
    burst (:meth:`add`).

    Parameters
    ----------
    profile : TdlProfile
        The TDL power-delay profile (its tap delays, s).
    num : Numerology
        The synthesis rate's numerology (n_fft, sample rate).
    """

    def __init__(self, profile: TdlProfile, num: Numerology):
        self.n, self.fs = num.n_fft, num.sample_rate_hz
        n, fs = self.n, self.fs
        self.k = np.fft.fftfreq(n, 1.0 / n)
        self.delays_s = np.asarray(profile.delays_s, dtype=np.float64)
        # the taps' spill (kernels.add_spill): tap l's copy of a symbol begins at most
        # ⌈τ_l F⌉ samples into its slot; column col_of[l, j] of ``spill_at`` evaluates a
        # symbol's waveform at sample j - τ_l F (e^{j2π k (j - τ_l F)/n}/n, as the IFFT)
        reach = np.ceil(self.delays_s * fs - 1e-9).astype(np.int64)
        self.spill_reach = reach
        self.spill_col_of = np.zeros((reach.size, int(reach.max(initial=0))), dtype=np.int64)
        cols = []
        for l, r in enumerate(reach):
            for j in range(r):
                self.spill_col_of[l, j] = len(cols)
                cols.append(j - self.delays_s[l] * fs)
        self.spill_at = (np.exp(2j * np.pi * np.outer(self.k, cols) / n) / n).astype(np.complex64)  # [n, Q]

    def add(self, z, u, rows, every, gains, n_c, tau0_s, sp, w_rad_s, t_first_s, phase0_rad) -> None:
        """Add the delayed taps' spill across symbol boundaries, which the cyclic read-out of
        each symbol's IFFT (:func:`kernels.place`) leaves out: the first b_l samples of a
        symbol's slot carry tap l's copy of the previous symbol, not of its own cyclic
        extension. With Δ_s = u_{s-1} e^{j2π k cp_{s-1}/n} - u_s (the tap-less spectra; a
        symbol not synthesized is empty), the correction at sample j of slot s is
        Σ_{l: j < b_l} g_{s,l} δ_s(j - τ_l F), δ_s the IFFT of Δ_s evaluated off the grid:
        one matrix product with :attr:`spill_at`. Exact (``tests/nr/test_fidelity.py``: the
        fast path equals the exact reference's per-symbol taps to float32 rounding). b_l uses
        the epoch's delay τ0 (under ``motion`` a symbol's edge moves by < 0.05 sample)."""
        n, fs = self.n, self.fs
        u_all = u if every else np.zeros((sp["symbols"].size, n), dtype=np.complex64)
        if not every:
            u_all[rows] = u
        if "cp_turn" not in sp:  # e^{j2π k cp_s/n} per symbol, cached with the layout
            cps, inv = np.unique(sp["cps"][:-1], return_inverse=True)
            sp["cp_turn"] = np.exp(2j * np.pi * np.outer(cps, self.k) / n).astype(np.complex64)[inv]
        cp_turn = sp["cp_turn"]
        delta = np.empty_like(u_all)
        np.multiply(u_all[:-1], cp_turn, out=delta[1:])
        delta[0] = 0
        delta -= u_all
        b = np.ceil((tau0_s + self.delays_s) * fs - 1e-9).astype(np.int64) - n_c
        b = np.clip(b, 0, self.spill_reach)
        kernels.add_spill(
            z,
            delta @ self.spill_at,
            self.spill_col_of,
            b,
            gains,
            sp["starts"],
            n_c,
            w_rad_s,
            t_first_s,
            phase0_rad,
            1.0 / fs,
        )
