"""The exact received burst: per-sample channel, every subcarrier, the train moving.

:func:`reference_received` synthesizes what the train receives with none of the fast
synthesizer's shortcuts (:class:`railradio.nr.synthesis.synthesizer.Synthesizer`), each of which it can
also switch on alone, so that the effect of every shortcut on the receiver's decisions is
measured (:mod:`railradio.nr.study.fidelity`).

The transmitted signal is TS 38.211 §5.3.1's time-continuous OFDM signal: each symbol the
sum of its subcarriers over its rectangular extent (cyclic prefix included). Every channel
tap delays it exactly — each symbol's subcarriers take the delay's phase, its extent moves by
the delay — and the receiver samples the sum at F_s/D:

* **band** — the rate of ``cfg.decimation``: D = 1 is the full rate with all 600 active
  subcarriers (exact up to the rectangular extents' spectrum beyond ±F_s/2, aliased);
  D = 8 keeps the central 128;
* **taps** — each Rayleigh tap's gain at every sample (exact) or held per symbol and
  rotated with the LOS phase inside it (``symbol_taps``, the production's model); the
  sum-of-sinusoids process is evaluated exactly every 16 full-rate samples and linearly
  interpolated in between (relative error ≤ (2π f_D Δt)²/8 ≤ 4e-6 at 468 km/h). Unlike the
  fast path, every tap's symbols keep their own delayed extent (the taps' spill into the
  next symbol is kept);
* **far links** — ``flat`` marks links sent as one non-fading tap with the profile's power
  (the interferers beyond ``nr.channel.full_channel_range_m``, when that is set);
* **geometry** — with ``motion`` (:class:`railradio.nr.channel.motion.BurstMotion`) the bulk delay,
  the LOS carrier phase and the beam gains follow the train through the burst; without it
  they are held at the epoch instant, as in production. The delay is taken symbol by symbol
  at each symbol's receive instant (its extent's edges at theirs): within a 4.5 µs symbol it
  changes by ≤ 2e-12 s at 468 km/h, a phase ≤ 1e-3 rad at the band's edge; the LOS phase
  follows every sample, the beam gains every symbol.

The random draws are those of :meth:`Synthesizer.draws` (pool indices, fading, beams, loads),
and the Rayleigh taps are evaluated on the fast path's clock (the transmit instant, receive
time minus the epoch's τ0), so that a shortcut's effect is measured on the same realization.
:func:`reference_correlation` is the time-domain correlation at every full-rate lag; the
receiver's front end between rates is :mod:`railradio.nr.receiver.frontend`.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np
import scipy.fft as sfft
from numpy.typing import NDArray

import railradio.nr.synthesis.kernels as kernels
from railradio.nr.channel.link import Links
from railradio.nr.channel.tdl import TdlProfile
from railradio.nr.receiver.config import ReceiverConfig
from railradio.nr.waveform.numerology import Numerology
from railradio.nr.waveform.ssb import burst_grid, reference_waveform

TAP_STEP_FULL = 16
"""Full-rate samples between exact evaluations of the sum-of-sinusoids taps."""


def _coarse_fading(
    profile: TdlProfile,
    doppler_hz: float,
    alpha: NDArray,
    phi: NDArray,
    t_first_s: float,
    dt_s: float,
    n_samples: int,
    step: int,
) -> NDArray[np.complex128]:
    """[C, L] sum-of-sinusoids tap gains, exact, at samples 0, step, 2·step, … past the
    last of ``n_samples`` samples ``dt_s`` apart from ``t_first_s`` (for linear
    interpolation in :func:`railradio.nr.synthesis.kernels.mix_taps`)."""
    amp_l = np.sqrt(profile.powers / alpha.shape[1])
    t_c = t_first_s + np.arange(n_samples // step + 2) * step * dt_s
    return kernels.sos_taps(amp_l, doppler_hz * np.cos(alpha), phi, t_c)


class _Layout(NamedTuple):
    """The samples of :func:`reference_received` at F_s/D, which every link shares."""

    num: Numerology
    symbols: NDArray[np.int64]
    k: NDArray[np.float64]  # subcarrier index of each FFT bin
    starts: NDArray[np.int64]  # each symbol's first sample (its CP start)
    cps: NDArray[np.int64]  # CP lengths [samples]
    total: int  # samples
    t0_s: float
    t: NDArray[np.float64]  # receive-sample times [s]
    t_sym: NDArray[np.float64]  # transmit-time centre of each symbol [s]
    block_of: NDArray[np.int64]  # SS block of each symbol (-1: none)
    cp_ramp: NDArray[np.complex128]  # [S, n]
    step: int  # samples between exact evaluations of the taps


def _layout(cfg: ReceiverConfig, symbols: NDArray[np.int64], t0_s: float, pool_ext: NDArray) -> _Layout:
    """The burst's samples and symbols at F_s/D (D = ``cfg.decimation``)."""
    num = Numerology(cfg.decimation)
    fs = num.sample_rate_hz
    n = num.n_fft
    k = np.fft.fftfreq(n, 1.0 / n)
    starts = num.symbol_start(symbols) - num.symbol_start(symbols[0])
    cps = num.cp_length(symbols)
    total = int(starts[-1] + n + cps[-1])
    s_first = float(num.symbol_start(symbols[0]))
    t = (np.arange(total) + s_first) / fs + t0_s  # receive-sample times
    # transmit-time centre of each symbol (the fast path's fading instants)
    t_sym = (num.symbol_start(symbols) + cps + n / 2) / fs + t0_s
    _, block_of = burst_grid(num, symbols, cfg.ssb_first, 0, 0, pool_ext, np.zeros(symbols.size, np.int64))
    cp_ramp = np.exp(-2j * np.pi * np.outer(cps, k) / n)  # [S, n]: the symbol's samples start at its CP
    step = max(1, TAP_STEP_FULL // cfg.decimation)
    return _Layout(num, symbols, k, starts, cps, total, t0_s, t, t_sym, block_of, cp_ramp, step)


def reference_received(
    cfg: ReceiverConfig,
    links: Links,
    profile: TdlProfile,
    pool: NDArray[np.complex64],
    draws: list[dict],
    symbols: NDArray[np.int64],
    t0_s: float = 0.0,
    at_train: NDArray[np.bool_] | None = None,
    *,
    motion=None,
    symbol_taps: bool = False,
    flat: NDArray[np.bool_] | None = None,
) -> NDArray[np.complex128]:
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
        :class:`railradio.nr.channel.motion.BurstMotion` of the links (exact geometry), or ``None``
        (held at the epoch instant: the production's shortcut).
    symbol_taps
        Rayleigh taps held per symbol (the production's shortcut) instead of per sample.
    flat
        [links] links sent as one non-fading tap (the production's far interferers).

    Returns
    -------
    ndarray, complex128 [n_samples]
    """
    at_train = np.ones(links.n, dtype=bool) if at_train is None else np.asarray(at_train, dtype=bool)
    flat = np.zeros(links.n, dtype=bool) if flat is None else np.asarray(flat, dtype=bool)
    pool_ext = np.vstack([pool, np.zeros((1, pool.shape[1]), pool.dtype)])  # last row: an idle slot
    lay = _layout(cfg, symbols, t0_s, pool_ext)
    n = lay.num.n_fft
    z = np.zeros(lay.total, dtype=complex)
    for r in range(links.n):
        m = (
            None
            if motion is None
            else dataclasses.replace(motion, link_rrh=motion.link_rrh[r : r + 1], panel_x_m=motion.panel_x_m[r : r + 1])
        )
        grid, beam = _link_grid(cfg, lay, links, r, draws[r], at_train[r], pool_ext, pool.shape[0])
        lin_phase = 2 * np.pi * links.f_los_hz[r] * lay.t + links.phase0[r]  # the production's LOS phase
        ba, tau_sym, tau_edge, excess = _link_geometry(lay, links, r, beam, m)
        los = np.exp(1j * (lin_phase + excess))
        spec = grid * (ba * links.amp[r] * n)[:, None] * lay.cp_ramp  # [S, n], × n: unnormalized IFFT
        taps, delayed = _delayed_taps(lay, profile, flat[r], spec, tau_sym, tau_edge)
        if flat[r] or not profile.powers.size:
            z += taps[0][0] * los * delayed[0]
            continue
        _add_fading_taps(z, lay, links, r, draws[r], profile, delayed, los, excess, symbol_taps)
    return z


def _link_grid(
    cfg: ReceiverConfig,
    lay: _Layout,
    links: Links,
    r: int,
    draw: dict,
    at_train_r: bool,
    pool_ext: NDArray,
    idle_row: int,
) -> tuple[NDArray, NDArray[np.int64]]:
    """Link ``r``'s resource grid [S, n] (an idle slot's data from row ``idle_row`` of
    ``pool_ext``) and each symbol's Tx beam [S]."""
    idx = draw["pool_idx"]
    data_beam = np.full(lay.symbols.size, int(np.argmin(np.abs(links.beam_amp[r] - links.data_amp[r]))))
    if not at_train_r:
        idx = np.where(draw["busy"], idx, idle_row)
        data_beam = draw["data_beam"]
    grid, _ = burst_grid(lay.num, lay.symbols, cfg.ssb_first, int(links.n_id1[r]), int(links.n_id2[r]), pool_ext, idx)
    beam = np.where(lay.block_of >= 0, lay.block_of, data_beam)
    return grid, beam


def _link_geometry(
    lay: _Layout, links: Links, r: int, beam: NDArray[np.int64], m
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Link ``r``'s beam amplitude per symbol [S], delay per symbol [S] and at each extent's
    edge [S + 1] [s], and LOS phase excess per sample [rad]: held at the epoch instant
    (``m`` ``None``) or from the link's motion ``m``. Returns ``(ba, tau_sym, tau_edge, excess)``."""
    num, symbols, cps, n = lay.num, lay.symbols, lay.cps, lay.num.n_fft
    fs = num.sample_rate_hz
    tau0 = float(links.tau_s[r])
    if m is None:
        ba = links.beam_amp[r][beam]
        tau_sym = np.full(symbols.size, tau0)  # the delay of each symbol [s]
        tau_edge = np.full(symbols.size + 1, tau0)  # at each extent's edge
        excess = np.zeros(lay.total)
    else:  # the geometry at each symbol's (and edge's) receive instant
        ba = m.beam_amp(lay.t_sym + tau0)[0, np.arange(symbols.size), beam]
        tau_sym = m.delay_s(lay.t_sym + tau0)[0]
        edges_t = (
            np.append(num.symbol_start(symbols), num.symbol_start(symbols[-1]) + n + cps[-1]) / fs + lay.t0_s + tau0
        )
        tau_edge = m.delay_s(edges_t)[0]
        excess = m.phase_excess_rad(lay.t)[0]
    return ba, tau_sym, tau_edge, excess


def _delayed_taps(
    lay: _Layout,
    profile: TdlProfile,
    flat_r: bool,
    spec: NDArray[np.complex128],
    tau_sym: NDArray[np.float64],
    tau_edge: NDArray[np.float64],
) -> tuple[list[tuple], NDArray[np.complex64]]:
    """The link's taps ``[(amplitude or None, delay [s])]`` (the LOS tap first, when the
    profile has one or the link is flat) and the burst delayed by each: every symbol's
    spectrum ``spec`` [S, n] with the delay's phase, placed at its delayed extent
    (complex64 [taps, samples])."""
    num, k, starts, total = lay.num, lay.k, lay.starts, lay.total
    fs, n = num.sample_rate_hz, num.n_fft
    buf = np.zeros(total, dtype=np.complex64)
    taps = (
        [(1.0 if flat_r else np.sqrt(profile.los_power), profile.los_delay_s)]
        if (flat_r or profile.los_power > 0)
        else []
    )
    if not flat_r:
        taps += [(None, d) for d in profile.delays_s]
    delayed = np.empty((len(taps), total), dtype=np.complex64)
    for j, (_, tau_l) in enumerate(taps):
        # sample m belongs to symbol s when (m + s_first)/fs - τ lies in its extent
        first = np.ceil((tau_edge + tau_l) * fs + np.append(starts, total) - 1e-9).astype(np.int64)
        first[-1] = max(first[-1], first[-2])
        shift = first[:-1] - starts - (tau_sym + tau_l) * fs  # the symbol's first sample past its start [samples]
        if np.ptp(shift) < 1e-9:  # held geometry: one sub-sample shift for every symbol
            ramp = np.exp(2j * np.pi * shift[0] * k / n)[None, :]
        else:
            ramp = np.exp(2j * np.pi * np.outer(shift, k) / n)
        y = np.fft.ifft(spec * ramp, axis=1).astype(np.complex64)
        buf[:] = 0
        kernels.place_symbols(buf, y, first)
        delayed[j] = buf
    return taps, delayed


def _add_fading_taps(
    z: NDArray[np.complex128],
    lay: _Layout,
    links: Links,
    r: int,
    draw: dict,
    profile: TdlProfile,
    delayed: NDArray[np.complex64],
    los: NDArray[np.complex128],
    excess: NDArray[np.float64],
    symbol_taps: bool,
) -> None:
    """Add link ``r``'s LOS and Rayleigh taps, each delayed copy of ``delayed`` times its
    gain, to ``z``: per sample (exact) or held per symbol (``symbol_taps``)."""
    fs, total, t, t_sym = lay.num.sample_rate_hz, lay.total, lay.t, lay.t_sym
    tau0 = float(links.tau_s[r])
    alpha, phi = draw["alpha"], draw["phi"]
    if symbol_taps:
        # production: gains at each symbol's transmit centre, relative to the LOS phase
        # there, rotated with the LOS phase inside the symbol (its receive samples)
        n_c = int(np.ceil(tau0 * fs - 1e-9))
        sym_of = np.clip(np.searchsorted(lay.starts + n_c, np.arange(total), side="right") - 1, 0, lay.symbols.size - 1)
        amp_l = np.sqrt(profile.powers / alpha.shape[1])
        coarse = kernels.sos_taps(amp_l, links.doppler_hz * np.cos(alpha), phi, t_sym)  # [S, L]
        coarse = coarse * np.exp(-1j * (2 * np.pi * links.f_los_hz[r] * t_sym + links.phase0[r]))[:, None]
        mult = los
    else:
        # every sample on the fast path's fading clock (transmit instant t - τ0), the
        # scattered taps riding on the LOS geometry (delay and phase curvature)
        sym_of = np.zeros(1, dtype=np.int64)
        coarse = _coarse_fading(profile, links.doppler_hz, alpha, phi, float(t[0] - tau0), 1.0 / fs, total, lay.step)
        mult = np.exp(1j * (2 * np.pi * links.f_los_hz[r] * tau0 + excess))
    if profile.los_power <= 0:  # NLOS profile: no LOS row
        delayed = np.vstack([np.zeros((1, total), np.complex64), delayed])
    kernels.mix_taps(
        z,
        delayed,
        np.ascontiguousarray(coarse),
        lay.step,
        sym_of,
        symbol_taps,
        mult,
        los,
        float(np.sqrt(profile.los_power)),
    )


def full_rate_noise(rng: np.random.Generator, links: Links, n_samples: int) -> NDArray[np.complex64]:
    """Complex white Gaussian noise of the train's receive chains at the full rate:
    variance N0 · F_s · chains per sample (its :func:`railradio.nr.receiver.frontend.project` by D has
    N0 · F_s/D · chains, the fast path's decimated-rate noise).

    Parameters
    ----------
    rng : numpy.random.Generator
        Generator of the noise.
    links : railradio.nr.channel.link.Links
        The epoch's links (``noise_psd_w_hz`` N0 [W/Hz] of one chain, ``n_chains``).
    n_samples : int
        Samples to draw.

    Returns
    -------
    numpy.ndarray of complex64
        [n_samples] noise samples at F_s (amplitude √W).
    """
    var = links.noise_psd_w_hz * Numerology(1).sample_rate_hz * links.n_chains
    return (np.float32(np.sqrt(var / 2)) * rng.standard_normal(2 * n_samples, dtype=np.float32)).view(np.complex64)


def reference_correlation(cfg: ReceiverConfig, z: NDArray, s_min: int, n_id1: int, n_id2: int) -> NDArray[np.float64]:
    """r̃_i[k] = |Σ_n b*[n] z[v_i + n + k]| at every full-rate lag k < K: [n_blocks, K].

    Parameters
    ----------
    cfg : ReceiverConfig
        SS-block pattern, block count and lag window K (``lags_full``).
    z : numpy.ndarray
        The burst's full-rate samples, [n_samples].
    s_min : int
        Symbol index of the burst's first sample.
    n_id1, n_id2 : int
        The cell's N_ID1 and N_ID2 (PSS+SSS reference).

    Returns
    -------
    numpy.ndarray
        |r̃_i[k]| at full-rate lags, [n_blocks, K].
    """
    num = Numerology(1)
    b = reference_waveform(num, n_id1, n_id2, int(cfg.ssb_first[0]))
    v = num.symbol_start(cfg.ssb_first) - num.symbol_start(s_min)
    out = np.zeros((cfg.n_blocks, cfg.lags_full))
    n = sfft.next_fast_len(cfg.lags_full + b.size)
    bf = np.conj(sfft.fft(b, n))
    for i, vi in enumerate(v):
        seg = np.zeros(n, dtype=complex)
        part = z[vi : vi + n]
        seg[: part.size] = part
        out[i] = np.abs(sfft.ifft(sfft.fft(seg) * bf)[: cfg.lags_full])
    return out
