"""Brute-force reference receiver: full rate, all 600 subcarriers, per-sample channel.

Used only to bound the shortcuts of :mod:`railradio.nr.receiver` on short cases (tests)
and as the naive baseline of the benchmark. Every RRH's transmit waveform is built at
F_s = 245.76 MHz (CP-OFDM, per-symbol beam gains); each TDL tap is delayed by its exact
τ0 + τ_l with a band-limited (FFT) fractional delay and multiplied by its tap gain evaluated
at every sample (LOS: continuous Doppler phase; Rayleigh: the same sum-of-sinusoids draws
as the fast path); the burst correlation is the time-domain r[m] = |Σ_n b*[n] z[n + m]| at
every full-rate lag.
"""

from __future__ import annotations

import numpy as np
import scipy.fft as sfft
from numpy.typing import NDArray

from railradio.nr.channel import TdlProfile, sos_eval
from railradio.nr.numerology import N_FFT, Numerology
from railradio.nr.receiver import Links, ReceiverConfig
from railradio.nr.ssb import burst_grid, reference_waveform


def reference_received(cfg: ReceiverConfig, links: Links, profile: TdlProfile, pool: NDArray[np.complex64],
                       draws: list[dict], symbols: NDArray[np.int64], t0_s: float = 0.0,
                       at_train: NDArray[np.bool_] | None = None) -> NDArray[np.complex128]:
    """Noiseless received samples at the full rate over ``symbols`` (index 0 = CP start of
    ``symbols[0]``), with the same draws as :meth:`Synthesizer.draws`.

    ``at_train`` [links]: the links whose data go toward the train (``None``: every link,
    the synthesizer's ``data_beam="train"``); the others send in their busy slots only, on
    their drawn beam (:class:`railradio.nr.receiver.Synthesizer`)."""
    num = Numerology(1)
    fs = num.sample_rate_hz
    starts = num.symbol_start(symbols) - num.symbol_start(symbols[0])
    cps = num.cp_length(symbols)
    total = int(starts[-1] + N_FFT + cps[-1])
    n_pad = sfft.next_fast_len(2 * total)
    f = sfft.fftfreq(n_pad, 1.0 / fs)
    t = (np.arange(total) + num.symbol_start(symbols[0])) / fs + t0_s
    z = np.zeros(total, dtype=complex)
    at_train = np.ones(links.n, dtype=bool) if at_train is None else np.asarray(at_train, dtype=bool)
    pool_ext = np.vstack([pool, np.zeros((1, pool.shape[1]), pool.dtype)])  # last row: an idle slot
    for r in range(links.n):
        idx, data = draws[r]["pool_idx"], links.data_amp[r]
        if not at_train[r]:
            idx = np.where(draws[r]["busy"], idx, pool.shape[0])
            data = links.beam_amp[r][draws[r]["data_beam"]]
        grid, block_of = burst_grid(num, symbols, cfg.ssb_first, int(links.n_id1[r]), int(links.n_id2[r]),
                                    pool_ext, idx)
        g = np.where(block_of >= 0, links.beam_amp[r][np.maximum(block_of, 0)], data) * links.amp[r]
        x = np.zeros(total, dtype=complex)
        for i in range(symbols.size):
            y = N_FFT * np.fft.ifft(grid[i]) * g[i]
            x[starts[i]:starts[i] + N_FFT + cps[i]] = np.concatenate([y[N_FFT - cps[i]:], y])
        xf = sfft.fft(x, n_pad)
        delays = np.concatenate([[profile.los_delay_s], profile.delays_s]) + links.tau_s[r]
        coef = np.empty((total, 1 + profile.powers.size), dtype=complex)
        coef[:, 0] = np.sqrt(profile.los_power) * np.exp(1j * (2 * np.pi * links.f_los_hz[r] * t + links.phase0[r]))
        if profile.powers.size:
            coef[:, 1:] = sos_eval(profile.powers, links.doppler_hz, t, draws[r]["alpha"], draws[r]["phi"])
        for l, tau in enumerate(delays):
            delayed = sfft.ifft(xf * np.exp(-2j * np.pi * f * tau))[:total]
            z += coef[:, l] * delayed
    return z


def reference_correlation(cfg: ReceiverConfig, z: NDArray, s_min: int, n_id1: int, n_id2: int) -> NDArray[np.float64]:
    """r̃_i[k] = |Σ_n b*[n] z[v_i + n + k]| at every full-rate lag k < K: [n_blocks, K]."""
    num = Numerology(1)
    b = reference_waveform(num, n_id1, n_id2, int(cfg.ssb_first[0]))
    v = num.symbol_start(cfg.ssb_first) - num.symbol_start(s_min)
    out = np.zeros((cfg.n_blocks, cfg.lags_full))
    n = sfft.next_fast_len(cfg.lags_full + b.size)
    bf = np.conj(sfft.fft(b, n))
    for i, vi in enumerate(v):
        seg = np.zeros(n, dtype=complex)
        part = z[vi: vi + n]
        seg[: part.size] = part
        out[i] = np.abs(sfft.ifft(sfft.fft(seg) * bf)[: cfg.lags_full])
    return out
