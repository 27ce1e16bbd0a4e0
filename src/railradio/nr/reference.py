"""The exact received burst: per-sample channel, every subcarrier, the train moving.

:func:`reference_received` synthesizes what the train receives with none of the fast
synthesizer's shortcuts (:class:`railradio.nr.receiver.Synthesizer`), each of which it can
also switch on alone, so that the effect of every shortcut on the receiver's decisions is
measured (:mod:`railradio.nr.fidelity`):

* **band** — at the rate F_s/D of ``cfg.decimation`` every subcarrier of that band: D = 1
  is the full rate with all 600 active subcarriers (exact); D = 8 keeps the central 128,
  the production's band;
* **taps** — each Rayleigh tap's gain at every sample (exact) or held per symbol and
  rotated with the LOS phase inside it (``symbol_taps``, the production's model); the
  sum-of-sinusoids process is evaluated exactly every 16 full-rate samples and linearly
  interpolated in between (relative error ≤ (2π f_D Δt)²/8 ≤ 4e-6 at 468 km/h);
* **far links** — ``flat`` marks links sent as one non-fading tap with the profile's power
  (the production's interferers beyond ``nr.channel.full_channel_range_m``);
* **geometry** — with ``motion`` (:class:`railradio.nr.motion.BurstMotion`) the bulk delay,
  the LOS carrier phase and the beam gains follow the train through the burst; without it
  they are held at the epoch instant, as in production. The time-varying delay
  x(t - τ(t)) is applied to every sample by a third-order Taylor expansion around the
  delay at the burst's middle (|δ| ≤ 0.11 full-rate samples at 468 km/h: the first
  omitted term is ≤ (2π · 72 MHz · |δ|)⁴/24 ≈ 7e-5 of the amplitude at the band edge); the
  beam gains are evaluated at each symbol's receive instant.

Every tap is delayed by its exact τ + τ_l with a band-limited (FFT) fractional delay. The
random draws are those of :meth:`Synthesizer.draws` (pool indices, fading, beams, loads), and
the Rayleigh taps are evaluated on the fast path's clock (the transmit instant, receive time
minus the epoch's τ0), so that a shortcut's effect is measured on the same realization.

:func:`reference_correlation` is the time-domain correlation at every full-rate lag; the
receiver's front end between rates is :mod:`railradio.nr.resample`.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.fft as sfft
from numpy.typing import NDArray

from railradio.nr import kernels
from railradio.nr.channel import TdlProfile
from railradio.nr.numerology import N_FFT, Numerology
from railradio.nr.receiver import Links, ReceiverConfig
from railradio.nr.ssb import burst_grid, reference_waveform

TAP_STEP_FULL = 16
"""Full-rate samples between exact evaluations of the sum-of-sinusoids taps."""


def _transmit(num: Numerology, grid: NDArray, g: NDArray, starts: NDArray, cps: NDArray,
              total: int) -> NDArray[np.complex64]:
    """CP-OFDM time signal of one RRH: each symbol's IFFT times its gain, its CP prepended."""
    n = num.n_fft
    y = (n * np.fft.ifft(grid, axis=1)) * g[:, None]
    x = np.zeros(total, dtype=np.complex64)
    for i in range(grid.shape[0]):
        x[starts[i]:starts[i] + n + cps[i]] = np.concatenate([y[i, n - cps[i]:], y[i]])
    return x


def _coarse_fading(profile: TdlProfile, doppler_hz: float, alpha: NDArray, phi: NDArray, t_first_s: float,
                   dt_s: float, n_samples: int, step: int) -> NDArray[np.complex128]:
    """[C, L] sum-of-sinusoids tap gains, exact, at samples 0, step, 2·step, … past the
    last of ``n_samples`` samples ``dt_s`` apart from ``t_first_s`` (for linear
    interpolation in :func:`railradio.nr.kernels.mix_taps`)."""
    amp_l = np.sqrt(profile.powers / alpha.shape[1])
    t_c = t_first_s + np.arange(n_samples // step + 2) * step * dt_s
    return kernels.sos_taps(amp_l, doppler_hz * np.cos(alpha), phi, t_c)


def reference_received(cfg: ReceiverConfig, links: Links, profile: TdlProfile, pool: NDArray[np.complex64],
                       draws: list[dict], symbols: NDArray[np.int64], t0_s: float = 0.0,
                       at_train: NDArray[np.bool_] | None = None, *, motion=None,
                       symbol_taps: bool = False, flat: NDArray[np.bool_] | None = None) -> NDArray[np.complex128]:
    """Noiseless received samples at F_s/D (D = ``cfg.decimation``) over ``symbols``
    (index 0 = CP start of ``symbols[0]``), with the draws of :meth:`Synthesizer.draws`.

    Parameters
    ----------
    cfg
        Its decimation sets the rate and the band synthesized (1: exact).
    links, profile, pool, draws, symbols, t0_s
        As the fast synthesizer takes them; ``pool`` [P, N_FFT] (full-rate bins).
    at_train
        [links] the links whose data go toward the train (``None``: every link); the others
        send in their busy slots only, on their drawn beam.
    motion
        :class:`railradio.nr.motion.BurstMotion` of the links (exact geometry), or ``None``
        (held at the epoch instant: the production's shortcut).
    symbol_taps
        Rayleigh taps held per symbol (the production's shortcut) instead of per sample.
    flat
        [links] links sent as one non-fading tap (the production's far interferers).

    Returns
    -------
    ndarray, complex128 [n_samples]
    """
    num = Numerology(cfg.decimation)
    fs = num.sample_rate_hz
    n = num.n_fft
    starts = num.symbol_start(symbols) - num.symbol_start(symbols[0])
    cps = num.cp_length(symbols)
    total = int(starts[-1] + n + cps[-1])
    # receive-sample times; the fast path's fading clock is the transmit instant
    t = (np.arange(total) + num.symbol_start(symbols[0])) / fs + t0_s
    at_train = np.ones(links.n, dtype=bool) if at_train is None else np.asarray(at_train, dtype=bool)
    flat = np.zeros(links.n, dtype=bool) if flat is None else np.asarray(flat, dtype=bool)
    pool_ext = np.vstack([pool, np.zeros((1, pool.shape[1]), pool.dtype)])  # last row: an idle slot
    tap_delays = np.concatenate([[profile.los_delay_s], profile.delays_s])
    max_delay = float(np.max(links.tau_s)) + float(tap_delays.max()) if links.n else 0.0
    n_pad = sfft.next_fast_len(total + int(np.ceil(max_delay * fs)) + 256)
    f = sfft.fftfreq(n_pad, 1.0 / fs)
    z = np.zeros(total, dtype=complex)
    # symbol layout: transmit-time centre of each symbol (the fast path's fading instants)
    t_sym = (num.symbol_start(symbols) + cps + n / 2) / fs + t0_s
    _, block_of = burst_grid(num, symbols, cfg.ssb_first, 0, 0, pool_ext, np.zeros(symbols.size, np.int64))
    e_taps = np.exp(-2j * np.pi * np.outer(tap_delays, f)).astype(np.complex64)  # [1 + L, n_pad]
    step = max(1, TAP_STEP_FULL // cfg.decimation)
    n_taps = profile.powers.size
    for r in range(links.n):
        tau0 = float(links.tau_s[r])
        m = None if motion is None else dataclasses.replace(
            motion, link_rrh=motion.link_rrh[r:r + 1], panel_x_m=motion.panel_x_m[r:r + 1])
        idx = draws[r]["pool_idx"]
        data_beam = np.full(symbols.size, int(np.argmin(np.abs(links.beam_amp[r] - links.data_amp[r]))))
        if not at_train[r]:
            idx = np.where(draws[r]["busy"], idx, pool.shape[0])
            data_beam = draws[r]["data_beam"]
        grid, _ = burst_grid(num, symbols, cfg.ssb_first, int(links.n_id1[r]), int(links.n_id2[r]), pool_ext, idx)
        beam = np.where(block_of >= 0, block_of, data_beam)
        # beam gains at the epoch instant, or at each symbol's receive instant
        ba = (links.beam_amp[r][beam] if m is None
              else m.beam_amp(t_sym + tau0)[0, np.arange(symbols.size), beam])
        x = _transmit(num, grid, ba * links.amp[r], starts, cps, total)
        xf = sfft.fft(x, n_pad)
        lin_phase = 2 * np.pi * links.f_los_hz[r] * t + links.phase0[r]  # the production's LOS phase
        excess = np.zeros(total)
        tau_c = tau0
        if m is not None:
            # x(t - τ(t)) = x̃(t - τ_c): x̃(u) = Σ_n (-δ)^n/n! x^(n)(u), δ = τ(u + τ_c) - τ_c
            tau_c = float(m.delay_s(np.array([t[total // 2]]))[0, 0])
            delta = m.delay_s(t + tau_c)[0] - tau_c  # [T] at transmit sample m
            w = 2j * np.pi * f
            xt = x.astype(complex)
            term = xf.astype(complex)
            for order, fact in ((1, 1.0), (2, 2.0), (3, 6.0)):
                term = term * w
                xt += ((-delta) ** order / fact) * sfft.ifft(term)[:total]
            xf = sfft.fft(xt.astype(np.complex64), n_pad)
            excess = m.phase_excess_rad(t)[0]
        los = np.exp(1j * (lin_phase + excess))
        spec = xf * np.exp(-2j * np.pi * f * tau_c).astype(np.complex64)
        if flat[r] or n_taps == 0:
            amp = 1.0 if flat[r] else np.sqrt(profile.los_power)
            z += amp * los * sfft.ifft(spec)[:total]
            continue
        delayed = sfft.ifft(spec[None, :] * e_taps, axis=-1)[:, :total]
        alpha, phi = draws[r]["alpha"], draws[r]["phi"]
        if symbol_taps:
            # production: gains at each symbol's transmit centre, relative to the LOS phase
            # there, rotated with the LOS phase inside the symbol (its receive samples)
            n_c = int(np.ceil(tau0 * fs - 1e-9))
            sym_of = np.clip(np.searchsorted(starts + n_c, np.arange(total), side="right") - 1, 0, symbols.size - 1)
            amp_l = np.sqrt(profile.powers / alpha.shape[1])
            coarse = kernels.sos_taps(amp_l, links.doppler_hz * np.cos(alpha), phi, t_sym)  # [S, L]
            coarse = coarse * np.exp(-1j * (2 * np.pi * links.f_los_hz[r] * t_sym + links.phase0[r]))[:, None]
            mult = los
        else:
            # every sample on the fast path's fading clock (transmit instant t - τ0), the
            # scattered taps riding on the LOS geometry (delay and phase curvature)
            sym_of = np.zeros(1, dtype=np.int64)
            coarse = _coarse_fading(profile, links.doppler_hz, alpha, phi, float(t[0] - tau0), 1.0 / fs, total, step)
            mult = np.exp(1j * (2 * np.pi * links.f_los_hz[r] * tau0 + excess))
        kernels.mix_taps(z, delayed, np.ascontiguousarray(coarse), step, sym_of, symbol_taps, mult, los,
                         float(np.sqrt(profile.los_power)))
    return z


def full_rate_noise(rng: np.random.Generator, links: Links, n_samples: int) -> NDArray[np.complex64]:
    """Complex white Gaussian noise of the train's receive chains at the full rate:
    variance N0 · F_s · chains per sample (its :func:`railradio.nr.resample.project` by D has
    N0 · F_s/D · chains,
    the fast path's decimated-rate noise)."""
    var = links.noise_psd_w_hz * Numerology(1).sample_rate_hz * links.n_chains
    return (np.float32(np.sqrt(var / 2)) * rng.standard_normal(2 * n_samples, dtype=np.float32)).view(np.complex64)


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


