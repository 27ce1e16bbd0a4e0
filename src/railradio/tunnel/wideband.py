"""The wideband receiver: the band-limited CIR of all slots' rays, its strongest peak's delay,
cable ranging from it and the +- / which-feed ambiguity resolved from all receivers."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import xarray as xr

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.tunnel.channel import offset_index, slot_powers, window_slots
from railradio.tunnel.geometry import Cable, Tunnel
from railradio.tunnel.measurement import MeasurementModel, field_at

BOLTZMANN_DBM_HZ = -174.0


def tone_response(table: xr.Dataset, mm: MeasurementModel) -> tuple[np.ndarray, np.ndarray]:
    """Baseband tone frequencies [tone] and every offset's frequency response [offset, tone]
    (taps at line-of-sight + excess delay: the line-of-sight phase times the taps' transform
    over the excess-delay grid), computed once per table.

    Parameters
    ----------
    table : xarray.Dataset
        Tabulated channel (:func:`railradio.tunnel.channel.tabulate`): ``taps``
        [offset_m, excess_delay_s], ``excess_delay_s`` [s], ``los_delay_s`` [offset_m] [s].
    mm : MeasurementModel
        ``n_tones`` and ``bandwidth_hz`` [Hz].

    Returns
    -------
    tuple of numpy.ndarray
        ``(f, resp)``: the tones' baseband frequencies, ``bandwidth_hz / n_tones`` apart
        around 0 [tone] [Hz], and each offset's complex frequency response relative to the
        cable power at the slot [offset, tone] [1].
    """
    n_t = mm.n_tones
    f = (np.arange(n_t) - n_t // 2) * (mm.bandwidth_hz / n_t)
    excess = np.exp(-2j * math.pi * table["excess_delay_s"].values[:, None] * f[None, :])  # [bin, tone]
    los = np.exp(-2j * math.pi * table["los_delay_s"].values[:, None] * f[None, :])  # [offset, tone]
    return f, los * (table["taps"].values @ excess)


def wideband_delays(
    table: xr.Dataset,
    tunnel: Tunnel,
    cable: Cable,
    x_rx_m: np.ndarray,
    rng,
    mm: MeasurementModel,
    tones=None,
    chunk: int = 1024,
    oversample: int = 16,
    thermal_noise: bool = True,
    shadow_db=None,
    slot_delay_s: np.ndarray | None = None,
) -> np.ndarray:
    """Delay of the strongest peak of the band-limited CIR at each receiver position [s]:
    ``n_tones`` tones across the bandwidth, thermal noise kT F B (``rng``; none without
    ``thermal_noise``), zero-padded IFFT (``oversample`` times), parabolic refinement of the
    peak.  The parabola's own error on a single path is below
    2 pi^2 / (45 sqrt(3) B oversample^3) (see :func:`peak_interp_bound_s`).

    Several Monte Carlo realizations of the place (each slot's shadowing) and of the noise
    at the same positions are computed together: the slots' tone responses are gathered
    once and every realization weighs them (one matrix product per receiver position).

    Parameters
    ----------
    table : xarray.Dataset
        Tabulated slot-to-receiver channel (:func:`railradio.tunnel.channel.tabulate`).
    tunnel : Tunnel
        Slot positions and tunnel length.
    cable : Cable
        The installed cable: power, delay and carrier phase at each slot.
    x_rx_m : numpy.ndarray
        Receiver positions along the tunnel [m], 1-D [rx].
    rng : numpy.random.Generator or None or sequence
        Source of the thermal noise; may be None without ``thermal_noise``; a sequence of R
        generators (or Nones) computes R realizations.
    mm : MeasurementModel
        ``n_tones``, ``bandwidth_hz`` [Hz], ``noise_figure_db`` [dB], ``window_m`` [m] (the
        slots within it of a receiver contribute; see :func:`wideband_view`).
    tones : tuple of numpy.ndarray or None
        :func:`tone_response` of ``table`` and ``mm``; None: computed here.
    chunk : int
        Scale of the number of receivers evaluated at a time (memory only).
    oversample : int
        Zero-padding factor of the IFFT.
    thermal_noise : bool
        Add thermal noise kT F B to every tone.
    shadow_db : numpy.ndarray or None or sequence
        Each slot's shadowing along the tunnel [slot, x on a 1 m grid] [dB]
        (:func:`railradio.tunnel.measurement.shadow_field`), applied to the slot's
        amplitude; one per realization when ``rng`` is a sequence; None: no shadowing.
    slot_delay_s : numpy.ndarray or None
        Extra delay of each slot's signal beyond the cable's nominal delay [slot] [s] (a
        feed's delay calibration error); None: none.

    Returns
    -------
    numpy.ndarray
        Delay of the strongest CIR peak [rx] (or [realization, rx] when ``rng`` is a
        sequence) [s], counted from the feeds (a path's delay is its cable delay plus its
        radio delay); the IFFT's range is n_tones / bandwidth_hz.

    Raises
    ------
    ValueError
        When ``shadow_db`` is a sequence whose length differs from ``rng``'s.
    """
    batched = isinstance(rng, (list, tuple))
    rngs = list(rng) if batched else [rng]
    shadows = list(shadow_db) if isinstance(shadow_db, (list, tuple)) else [shadow_db] * len(rngs)
    if len(shadows) != len(rngs):
        raise ValueError("shadow_db must hold one field per realization of rng")
    xs, pc_dbm, tc = slot_powers(tunnel, cable)
    if slot_delay_s is not None:
        tc = tc + np.asarray(slot_delay_s, dtype=float)
    amp_c = 10.0 ** ((pc_dbm - 30.0) / 20.0) * np.exp(-2j * math.pi * cable.frequency_hz * tc)
    f, resp = tones if tones is not None else tone_response(table, mm)
    cab_tones = amp_c[:, None] * np.exp(-2j * math.pi * tc[:, None] * f[None, :])  # [slot, tone]
    df = f[1] - f[0]
    noise_w = 10.0 ** ((BOLTZMANN_DBM_HZ + mm.noise_figure_db - 30.0) / 10.0) * mm.bandwidth_hz
    n_fft = f.size * oversample
    x_all = np.asarray(x_rx_m, dtype=float)
    n_r = len(rngs)
    out = np.empty((n_r, x_all.size))
    # receivers per pass: the [receiver, slot, tone] arrays stay near chunk x 20 x 64 elements
    chunk = max(16, chunk * 1280 // (f.size * (2 * int(mm.window_m // tunnel.slot_spacing_m) + 2)))
    for a in range(0, x_all.size, chunk):
        x = x_all[a : a + chunk]
        sl, ok = window_slots(tunnel, x, mm.window_m)
        idx, inside = offset_index(table, x[:, None] - xs[sl])
        g = cab_tones[sl] * resp[idx] * (ok & inside)[..., None]  # [rx, slot, tone]
        w = np.stack(
            [np.ones(sl.shape) if s is None else 10.0 ** (field_at(s, sl, x[:, None]) / 20.0) for s in shadows]
        )
        # every realization weighs the same gathered responses: [rx, R, slot] @ [rx, slot, tone]
        gr = g.view(np.float64).reshape(g.shape[0], g.shape[1], 2 * g.shape[2])
        hf = np.matmul(np.ascontiguousarray(w.transpose(1, 0, 2)), gr).view(np.complex128)  # [rx, R, tone]
        hf = np.ascontiguousarray(hf.transpose(1, 0, 2))  # [R, rx, tone]
        if thermal_noise:
            for r, gen in enumerate(rngs):
                hf[r] += math.sqrt(noise_w / 2.0) * (
                    gen.standard_normal(hf.shape[1:]) + 1j * gen.standard_normal(hf.shape[1:])
                )
        cir = np.abs(np.fft.ifft(hf.reshape(-1, f.size), n=n_fft, axis=1)) ** 2
        k = np.argmax(cir, axis=1)
        rows = np.arange(cir.shape[0])
        y0, y1, y2 = cir[rows, (k - 1) % n_fft], cir[rows, k], cir[rows, (k + 1) % n_fft]
        den = y0 - 2 * y1 + y2
        frac = np.where(den < 0, 0.5 * (y0 - y2) / np.where(den < 0, den, -1.0), 0.0)
        out[:, a : a + chunk] = ((k + frac) / (n_fft * df)).reshape(n_r, x.size)
    return out if batched else out[0]


def wideband_view(table: xr.Dataset, mm: MeasurementModel) -> MeasurementModel:
    """The wideband receiver sees every slot of the table (by default the whole tunnel), not
    only those within ``window_m`` (which chooses the separable receiver's slots); a shorter
    table's cut-off is measured by :func:`railradio.tunnel.engine_checks.cutoff_check`.

    Parameters
    ----------
    table : xarray.Dataset
        Tabulated channel; its largest offset ``offset_m`` [m] is its extent.
    mm : MeasurementModel
        The receivers' measurement model.

    Returns
    -------
    MeasurementModel
        A copy of ``mm`` whose ``window_m`` is the larger of its own and the table's extent [m].
    """
    return dataclasses.replace(mm, window_m=max(mm.window_m, float(table["offset_m"].values[-1])))


def peak_interp_bound_s(bandwidth_hz: float, oversample: int) -> float:
    """Largest error of the three-point parabolic peak estimate on a single band-limited
    path [s].  Near its peak the pulse |sinc(B t)|^2 = 1 - a t^2 + b t^4 with
    a = pi^2 B^2 / 3, b = 2 pi^4 B^4 / 45; samples at delta + (-D, 0, D), D = 1/(B os),
    |delta| <= D/2, put the parabola's vertex at -(b/a) delta (4 delta^2 - D^2) to first
    order in b/a, whose largest magnitude (at delta = D / (2 sqrt 3)) is
    (b/a) D^3 / (3 sqrt 3) = 2 pi^2 / (45 sqrt(3) B os^3).  (The 64-tone Dirichlet kernel
    differs from the sinc by O(1/N^2); the next order in b/a D^2 = 2 pi^2/(15 os^2), 0.5 %
    at os = 16: a 10 % margin covers both.)

    Parameters
    ----------
    bandwidth_hz : float
        Bandwidth B [Hz]; positive.
    oversample : int
        Zero-padding factor os of the IFFT; >= 2.

    Returns
    -------
    float
        Bound on the peak's delay error with the 10 % margin [s].

    Raises
    ------
    ValueError
        When ``bandwidth_hz`` is not positive or ``oversample`` < 2.
    """
    if not bandwidth_hz > 0 or oversample < 2:
        raise ValueError("bandwidth_hz must be positive and oversample >= 2")
    return 1.1 * 2.0 * math.pi**2 / (45.0 * math.sqrt(3.0) * bandwidth_hz * oversample**3)


def cable_model_delay_s(x_m: np.ndarray, tunnel: Tunnel, cable: Cable) -> np.ndarray:
    """The receiver's delay model: cable delay to the nearest cable point plus h / c [s].

    Parameters
    ----------
    x_m : numpy.ndarray
        Receiver positions along the tunnel [m], any shape.
    tunnel : Tunnel
        Tunnel length and cross distance h between slot line and receiver.
    cable : Cable
        Feeds and velocity factor.

    Returns
    -------
    numpy.ndarray
        Model delay [s], the shape of ``x_m``.
    """
    return cable.cable_delay_s(x_m, tunnel.length_m) + tunnel.cross_distance_m / SPEED_OF_LIGHT_M_S


def wideband_candidates(
    tau_s: np.ndarray,
    tunnel: Tunnel,
    cable: Cable,
    bias_s: float = 0.0,
    velocity_factor: float | None = None,
    feed_delay_s: np.ndarray | None = None,
) -> np.ndarray:
    """Cable ranging x = x_feed +- v c (tau - bias - d_feed - h/c) for every feed [epoch,
    2 n_feeds]; which one is right the tracker decides (nearest its prediction).

    Parameters
    ----------
    tau_s : numpy.ndarray
        CIR peak delays (:func:`wideband_delays`) [s], [epoch].
    tunnel : Tunnel
        Tunnel length and cross distance h between slot line and receiver.
    cable : Cable
        Feeds, feed spacing and velocity factor.
    bias_s : float
        Calibrated delay bias of the peak, subtracted first [s].
    velocity_factor : float or None
        The velocity factor v the receiver assumes; None: the cable's.
    feed_delay_s : numpy.ndarray or None
        The extra delay d_feed the receiver assumes for each feed [feed] [s] (its
        calibration database; nonzero entries model calibration errors); None: zeros.

    Returns
    -------
    numpy.ndarray
        Candidate positions [epoch, 2 n_feeds] [m]: x_feed - r for every feed, then
        x_feed + r, with the range r clipped to [0, feed_spacing_m / 2] and the positions to
        the tunnel.

    Raises
    ------
    ValueError
        When ``feed_delay_s`` has not one entry per feed or ``velocity_factor`` is not in (0, 1].
    """
    feeds = cable.feed_x_m(tunnel.length_m)
    v = cable.velocity_factor if velocity_factor is None else velocity_factor
    if not 0.0 < v <= 1.0:
        raise ValueError(f"velocity_factor must be in (0, 1], got {v!r}")
    d = np.zeros(feeds.size) if feed_delay_s is None else np.asarray(feed_delay_s, dtype=float)
    if d.shape != feeds.shape:
        raise ValueError(f"feed_delay_s must have one entry per feed ({feeds.size}), got shape {d.shape}")
    half = cable.feed_spacing_m / 2.0
    tau = np.asarray(tau_s, dtype=float)[:, None] - d[None, :]  # [epoch, feed]
    r = np.clip(v * SPEED_OF_LIGHT_M_S * (tau - bias_s - tunnel.cross_distance_m / SPEED_OF_LIGHT_M_S), 0.0, half)
    cand = np.concatenate([feeds[None, :] - r, feeds[None, :] + r], axis=1)
    return np.clip(cand, 0.0, tunnel.length_m)


def resolve_ambiguity(
    cand_m: np.ndarray, offsets_m: np.ndarray, feed_spacing_m: float, start_m: tuple[float, float], gate_m: float
) -> tuple[np.ndarray, np.ndarray]:
    """Resolve the wideband fixes' +- / which-feed ambiguity from the measurements alone [ours].

    ``cand_m`` [epoch, receiver, candidate]: every receiver's cable-ranging candidates
    (:func:`wideband_candidates`); receiver k sits ``offsets_m[k]`` behind the head.  Every
    candidate of every receiver proposes a head position h = c + offset_k; each proposal
    is scored by the truncated squared misfit of all receivers,
    sum_k min(min_m |c_km + offset_k - h|, gate_m)^2 (robust to one receiver's wrong peak),
    and the best proposal wins.  On the two sides of a feed the receivers' delays run in
    opposite directions along the train, so the +- is decided by the measurements; the
    misfit is periodic in the feed spacing (identical feed sections), so proposals are only
    taken within half a feed spacing of the previous epoch's head (continuity; a train
    moves metres per epoch), starting from ``start_m`` = (lo, hi): the head is in that
    interval at the first epoch (the entry prior: the first feed section).
    Returns the head proposal [epoch] and each receiver's chosen candidate [epoch, receiver].

    Parameters
    ----------
    cand_m : numpy.ndarray
        Every receiver's candidate positions [m], [epoch, receiver, candidate].
    offsets_m : numpy.ndarray
        Each receiver's distance behind the head [m], [receiver].
    feed_spacing_m : float
        Length of the cable section of one feed [m]; positive.
    start_m : tuple of float
        Interval (lo, hi) that holds the head at the first epoch [m].
    gate_m : float
        Truncation of each receiver's misfit [m]; positive.

    Returns
    -------
    tuple of numpy.ndarray
        ``(head, fix)``: the head position [epoch] [m] and each receiver's chosen
        candidate [epoch, receiver] [m].

    Raises
    ------
    ValueError
        When ``offsets_m`` has not one entry per receiver, or ``gate_m`` or
        ``feed_spacing_m`` is not positive.
    """
    c = np.asarray(cand_m, dtype=float)
    off = np.asarray(offsets_m, dtype=float)
    n_e, k, n_c = c.shape
    if off.shape != (k,):
        raise ValueError("offsets_m must have one entry per receiver")
    if not gate_m > 0 or not feed_spacing_m > 0:
        raise ValueError("gate_m and feed_spacing_m must be positive")
    prop_all = (c + off[None, :, None]).reshape(n_e, k * n_c)  # head proposals
    head = np.empty(n_e)
    lo, hi = start_m
    half = feed_spacing_m / 2.0
    for t in range(n_e):
        p = prop_all[t]
        ok = (p >= lo) & (p <= hi)
        if not np.any(ok):  # nothing in the window: keep the previous head
            head[t] = head[t - 1] if t else 0.5 * (lo + hi)
        else:
            p = p[ok]
            mis = np.min(np.abs(prop_all[t].reshape(k, n_c)[None, :, :] - p[:, None, None]), axis=2)
            cost = np.sum(np.minimum(mis, gate_m) ** 2, axis=1)
            head[t] = p[np.argmin(cost)]
        lo, hi = head[t] - half, head[t] + half
    want = head[:, None] - off[None, :]
    pick = np.argmin(np.abs(c - want[..., None]), axis=2)
    fix = np.take_along_axis(c, pick[..., None], axis=2)[..., 0]
    return head, fix


def ambiguity_wrong(cand_m: np.ndarray, fix_m: np.ndarray, x_true_m: np.ndarray, separation_m: float) -> np.ndarray:
    """Whether each fix took the wrong candidate [epoch, receiver]: not the candidate nearest
    the truth, while that one lies more than ``separation_m`` away from the chosen one (near
    a feed or a section end the two sides coincide and the choice does not matter).

    Parameters
    ----------
    cand_m : numpy.ndarray
        Every receiver's candidate positions [m], [epoch, receiver, candidate].
    fix_m : numpy.ndarray
        The chosen candidates [m], [epoch, receiver].
    x_true_m : numpy.ndarray
        True receiver positions [m], [epoch, receiver].
    separation_m : float
        Distance between the chosen and the right candidate above which the choice is
        wrong [m].

    Returns
    -------
    numpy.ndarray
        Boolean [epoch, receiver]: True where the fix took a wrong candidate.
    """
    c = np.asarray(cand_m, dtype=float)
    best = np.take_along_axis(c, np.argmin(np.abs(c - np.asarray(x_true_m)[..., None]), axis=2)[..., None], axis=2)[
        ..., 0
    ]
    return np.abs(best - np.asarray(fix_m)) > separation_m
