"""A train crossing the tunnel: measurements, snapshot fixes, tracks (seed 003 §3.3, §7.2).

Measurement models (docs/model/tunnel.md §3, both reported):

* ``separable`` - the seed's assumption that every slot's RSSI and delay are measured on
  their own [seed 4.2, 6.2]: per slot the coherent one-slot power of the channel table
  (its own multipath fading) plus log-normal shadowing (a spatial field per slot along the
  tunnel, correlated over ``shadow_corr_m``, the same for every train: it belongs to the
  place), and the line-of-sight delay plus Gaussian error; the ``n_slots`` strongest
  measured slots within ``window_m`` are used.  Fix: RSSI ranging + linearized LS, then
  TDOA Gauss-Newton from it.  The delay error is ``white`` (independent per epoch and
  slot, the seed's assumption, which a 20 Hz filter averages away), ``ar1`` (per slot an
  AR(1) field along the track, correlated over ``delay_corr_m``: a multipath bias that
  changes with position) or ``slot_bias`` (per slot one constant bias: a calibration error
  of the slot's delay); same sigma in all three.
* ``wideband`` - what a receiver of bandwidth B actually sees: the sum of all slots'
  rays (every slot of the table, :func:`wideband_view`) with their cable delays (velocity
  factor v), sampled on ``n_tones`` tones across
  B with thermal noise, transformed to a channel impulse response; its strongest peak
  gives a delay that maps to the cable distance from the feed, x = x_feed +- v c (tau - h/c).
  The +- is resolved from the measurements (:func:`resolve_ambiguity`: the K receivers sit
  at known offsets along the train, and on the two sides of a feed their delays run in
  opposite directions); which feed (the cable is periodic, no measurement can tell) by
  continuity from the tunnel entry (the head is in the first feed section when the whole
  train has entered), never from the truth.

Every filter starts from the first snapshot fix with its variance (speed 0 +- the maximum
speed), not from the true position.

The train: K receivers evenly along its length [seed 3.3.1], constant speed, whole train
inside the tunnel; epochs at ``rate_hz``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy.signal import lfilter

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.rng import make_rng, spawn_key
from railradio.tunnel.channel import offset_index, slot_powers, window_slots
from railradio.tunnel.geometry import Cable, Tunnel
from railradio.tunnel.positioning import (
    gain_to_offset_m,
    gdop_seed,
    gdop_tdoa_along,
    monotone_gain_db,
    range_diff_from_delays,
    rssi_ls,
    tdoa_gauss_newton,
)
from railradio.tunnel.tracking import kf_track, kf_track_batch, pf_track, robust_variance

BOLTZMANN_DBM_HZ = -174.0
TRAIN_IDS = {"metro": 1, "hst": 2, "freight": 3}
MEASUREMENTS = ("separable", "wideband")
VARIANT_IDS = {
    ("physical", "separable"): 1,
    ("physical", "wideband"): 2,
    ("seed", "separable"): 3,
    ("seed", "wideband"): 4,
}
SHADOW_KEY = {"evaluation": 100, "calibration": 101}
DELAY_KEY = {"evaluation": 102, "calibration": 103}
DELAY_ERRORS = ("white", "ar1", "slot_bias")


@dataclass(frozen=True)
class MeasurementModel:
    shadow_sigma_db: float = 4.0
    shadow_corr_m: float = 10.0
    delay_sigma_s: float = 20e-9
    n_slots: int = 8
    window_m: float = 200.0
    bandwidth_hz: float = 5e6
    n_tones: int = 64
    noise_figure_db: float = 7.0
    delay_error: str = "white"
    delay_corr_m: float = 20.0

    def __post_init__(self) -> None:
        if self.delay_error not in DELAY_ERRORS:
            raise ValueError(f"delay_error must be one of {DELAY_ERRORS}, got {self.delay_error!r}")
        if not self.delay_corr_m > 0:
            raise ValueError(f"delay_corr_m must be positive, got {self.delay_corr_m!r}")
        if self.n_slots < 3:
            raise ValueError(f"n_slots must be >= 3, got {self.n_slots!r}")
        for name in ("shadow_corr_m", "delay_sigma_s", "window_m", "bandwidth_hz"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)!r}")
        if self.shadow_sigma_db < 0:
            raise ValueError("shadow_sigma_db must be >= 0")


@dataclass(frozen=True)
class Train:
    name: str
    length_m: float
    speed_kmh: float
    n_receivers: int = 4

    def __post_init__(self) -> None:
        if self.n_receivers < 2:
            raise ValueError("n_receivers must be >= 2 (head and tail)")
        if not self.length_m > 0 or not self.speed_kmh > 0:
            raise ValueError("length_m and speed_kmh must be positive")

    @property
    def receiver_offsets_m(self) -> np.ndarray:
        """Receiver k at x_head - k L / (K - 1) [seed 3.3.1]."""
        return np.arange(self.n_receivers) * self.length_m / (self.n_receivers - 1)


def shadow_field(
    rng: np.random.Generator, n_slots: int, length_m: float, sigma_db: float, corr_m: float, step_m: float = 1.0
) -> np.ndarray:
    """Per-slot shadowing along the tunnel [slot, x on a ``step_m`` grid] [dB], AR(1) with
    correlation exp(-dx / corr_m) (Gudmundson)."""
    n = int(math.ceil(length_m / step_m)) + 1
    rho = math.exp(-step_m / corr_m)
    w = rng.standard_normal((n_slots, n))
    w[:, 1:] *= math.sqrt(1.0 - rho * rho)
    return sigma_db * lfilter([1.0], [1.0, -rho], w, axis=1)


def delay_error_field(
    rng: np.random.Generator, n_slots: int, length_m: float, mm: MeasurementModel
) -> np.ndarray | None:
    """Per-slot delay error along the tunnel [slot, x on a 1 m grid] [s]; None if white."""
    if mm.delay_error == "white":
        return None
    if mm.delay_error == "ar1":
        return shadow_field(rng, n_slots, length_m, mm.delay_sigma_s, mm.delay_corr_m)
    n = int(math.ceil(length_m)) + 1
    return np.repeat(mm.delay_sigma_s * rng.standard_normal((n_slots, 1)), n, axis=1)


def _field_at(field: np.ndarray, slots: np.ndarray, x_m: np.ndarray, step_m: float = 1.0) -> np.ndarray:
    pos = np.clip(x_m / step_m, 0, field.shape[1] - 1.000001)
    i0 = pos.astype(np.int64)
    fr = pos - i0
    return field[slots, i0] * (1 - fr) + field[slots, i0 + 1] * fr


def separable_measurements(
    table: xr.Dataset,
    tunnel: Tunnel,
    cable: Cable,
    x_rx_m: np.ndarray,
    shadow: np.ndarray,
    rng: np.random.Generator,
    mm: MeasurementModel,
    propagation: str,
    delay_field: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Per-slot RSSI and delay of the ``n_slots`` strongest measured slots [epoch, n];
    the delay error is white from ``rng`` or read from ``delay_field`` (see
    :func:`delay_error_field`)."""
    xs, pc_dbm, _ = slot_powers(tunnel, cable)
    x = np.asarray(x_rx_m, dtype=float)
    sl, ok = window_slots(tunnel, x, mm.window_m)
    idx, inside = offset_index(table, x[:, None] - xs[sl])
    if propagation == "physical":
        gain_db = 20.0 * np.log10(np.abs(table["taps"].values.sum(axis=1)))[idx]
    else:
        gain_db = 10.0 * np.log10(table["power_mean"].values)[idx]
    rssi = pc_dbm[sl] + gain_db + _field_at(shadow, sl, x[:, None])
    rssi = np.where(ok & inside, rssi, -np.inf)
    order = np.argsort(-rssi, axis=1, kind="stable")[:, : mm.n_slots]
    pick = np.take_along_axis(sl, order, axis=1)
    rssi = np.take_along_axis(rssi, order, axis=1)
    if not np.all(np.isfinite(rssi)):
        raise ValueError(f"fewer than n_slots={mm.n_slots} slots within window_m={mm.window_m}")
    h = tunnel.cross_distance_m
    delay = np.sqrt((x[:, None] - xs[pick]) ** 2 + h * h) / SPEED_OF_LIGHT_M_S
    if delay_field is None:
        delay = delay + mm.delay_sigma_s * rng.standard_normal(pick.shape)
    else:
        delay = delay + _field_at(delay_field, pick, np.broadcast_to(x[:, None], pick.shape))
    return {"slot": pick, "slot_x_m": xs[pick], "rssi_dbm": rssi, "cable_power_dbm": pc_dbm[pick], "delay_s": delay}


def separable_fix(meas: dict, table: xr.Dataset, tunnel: Tunnel, mm: MeasurementModel):
    """RSSI-LS fix, TDOA fix from it, its variance, both GDOPs [epoch]."""
    h = tunnel.cross_distance_m
    off, curve = monotone_gain_db(table)
    dx = gain_to_offset_m(meas["rssi_dbm"] - meas["cable_power_dbm"], off, curve)
    x_rssi = rssi_ls(meas["slot_x_m"], np.sqrt(dx**2 + h * h), h)
    x_rssi = np.clip(x_rssi, 0.0, tunnel.length_m)
    sig = SPEED_OF_LIGHT_M_S * mm.delay_sigma_s
    x_tdoa, var = tdoa_gauss_newton(x_rssi, meas["slot_x_m"], range_diff_from_delays(meas["delay_s"]), h, sig)
    gd_seed = gdop_seed(x_tdoa, tunnel.rx_y_m, meas["slot_x_m"], tunnel.slot_yz[0])
    gd_tdoa = gdop_tdoa_along(x_tdoa, meas["slot_x_m"], h)
    return x_rssi, x_tdoa, np.sqrt(var), gd_seed, gd_tdoa


def tone_response(table: xr.Dataset, mm: MeasurementModel) -> tuple[np.ndarray, np.ndarray]:
    """Baseband tone frequencies [tone] and every offset's frequency response [offset, tone]
    (taps at line-of-sight + excess delay: the line-of-sight phase times the taps' transform
    over the excess-delay grid), computed once per table."""
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
    rng: np.random.Generator | None,
    mm: MeasurementModel,
    tones=None,
    chunk: int = 1024,
    oversample: int = 16,
    thermal_noise: bool = True,
) -> np.ndarray:
    """Delay of the strongest peak of the band-limited CIR at each receiver position [s]:
    ``n_tones`` tones across the bandwidth, thermal noise kT F B (``rng``; none without
    ``thermal_noise``), zero-padded IFFT (``oversample`` times), parabolic refinement of the
    peak.  The parabola's own error on a single path is below
    2 pi^2 / (45 sqrt(3) B oversample^3) (see :func:`peak_interp_bound_s`)."""
    xs, pc_dbm, tc = slot_powers(tunnel, cable)
    amp_c = 10.0 ** ((pc_dbm - 30.0) / 20.0) * np.exp(-2j * math.pi * cable.frequency_hz * tc)
    f, resp = tones if tones is not None else tone_response(table, mm)
    cab_tones = amp_c[:, None] * np.exp(-2j * math.pi * tc[:, None] * f[None, :])  # [slot, tone]
    df = f[1] - f[0]
    noise_w = 10.0 ** ((BOLTZMANN_DBM_HZ + mm.noise_figure_db - 30.0) / 10.0) * mm.bandwidth_hz
    n_fft = f.size * oversample
    x_all = np.asarray(x_rx_m, dtype=float)
    out = np.empty(x_all.size)
    # receivers per pass: the [receiver, slot, tone] arrays stay near chunk x 20 x 64 elements
    chunk = max(16, chunk * 1280 // (f.size * (2 * int(mm.window_m // tunnel.slot_spacing_m) + 2)))
    for a in range(0, x_all.size, chunk):
        x = x_all[a : a + chunk]
        sl, ok = window_slots(tunnel, x, mm.window_m)
        idx, inside = offset_index(table, x[:, None] - xs[sl])
        w = (ok & inside)[..., None]
        cab = cab_tones[sl]
        hf = np.sum(cab * resp[idx] * w, axis=1)
        if thermal_noise:
            hf += math.sqrt(noise_w / 2.0) * (rng.standard_normal(hf.shape) + 1j * rng.standard_normal(hf.shape))
        cir = np.abs(np.fft.ifft(hf, n=n_fft, axis=1)) ** 2
        k = np.argmax(cir, axis=1)
        rows = np.arange(x.size)
        y0, y1, y2 = cir[rows, (k - 1) % n_fft], cir[rows, k], cir[rows, (k + 1) % n_fft]
        den = y0 - 2 * y1 + y2
        frac = np.where(den < 0, 0.5 * (y0 - y2) / np.where(den < 0, den, -1.0), 0.0)
        out[a : a + chunk] = (k + frac) / (n_fft * df)
    return out


def wideband_view(table: xr.Dataset, mm: MeasurementModel) -> MeasurementModel:
    """The wideband receiver sees every slot of the table (by default the whole tunnel), not
    only those within ``window_m`` (which chooses the separable receiver's slots); a shorter
    table's cut-off is measured by :func:`railradio.tunnel.study.cutoff_check`."""
    return dataclasses.replace(mm, window_m=max(mm.window_m, float(table["offset_m"].values[-1])))


def peak_interp_bound_s(bandwidth_hz: float, oversample: int) -> float:
    """Largest error of the three-point parabolic peak estimate on a single band-limited
    path [s].  Near its peak the pulse |sinc(B t)|^2 = 1 - a t^2 + b t^4 with
    a = pi^2 B^2 / 3, b = 2 pi^4 B^4 / 45; samples at delta + (-D, 0, D), D = 1/(B os),
    |delta| <= D/2, put the parabola's vertex at -(b/a) delta (4 delta^2 - D^2) to first
    order in b/a, whose largest magnitude (at delta = D / (2 sqrt 3)) is
    (b/a) D^3 / (3 sqrt 3) = 2 pi^2 / (45 sqrt(3) B os^3).  (The 64-tone Dirichlet kernel
    differs from the sinc by O(1/N^2); the next order in b/a D^2 = 2 pi^2/(15 os^2), 0.5 %
    at os = 16: a 10 % margin covers both.)"""
    if not bandwidth_hz > 0 or oversample < 2:
        raise ValueError("bandwidth_hz must be positive and oversample >= 2")
    return 1.1 * 2.0 * math.pi**2 / (45.0 * math.sqrt(3.0) * bandwidth_hz * oversample**3)


def cable_model_delay_s(x_m: np.ndarray, tunnel: Tunnel, cable: Cable) -> np.ndarray:
    """The receiver's delay model: cable delay to the nearest cable point plus h / c [s]."""
    return cable.cable_delay_s(x_m, tunnel.length_m) + tunnel.cross_distance_m / SPEED_OF_LIGHT_M_S


def wideband_candidates(tau_s: np.ndarray, tunnel: Tunnel, cable: Cable, bias_s: float = 0.0) -> np.ndarray:
    """Cable ranging x = x_feed +- v c (tau - bias - h/c) for every feed [epoch, 2 n_feeds];
    which one is right the tracker decides (nearest its prediction)."""
    feeds = cable.feed_x_m(tunnel.length_m)
    half = cable.feed_spacing_m / 2.0
    r = (
        cable.velocity_factor
        * SPEED_OF_LIGHT_M_S
        * (np.asarray(tau_s) - bias_s - tunnel.cross_distance_m / SPEED_OF_LIGHT_M_S)
    )
    r = np.clip(r, 0.0, half)
    cand = np.concatenate([feeds[None, :] - r[:, None], feeds[None, :] + r[:, None]], axis=1)
    return np.clip(cand, 0.0, tunnel.length_m)


def resolve_ambiguity(
    cand_m: np.ndarray, offsets_m: np.ndarray, feed_spacing_m: float, start_m: tuple[float, float], gate_m: float
) -> tuple[np.ndarray, np.ndarray]:
    """Resolve the wideband fixes' +- / which-feed ambiguity from the measurements [seed-free].

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
    a feed or a section end the two sides coincide and the choice does not matter)."""
    c = np.asarray(cand_m, dtype=float)
    best = np.take_along_axis(c, np.argmin(np.abs(c - np.asarray(x_true_m)[..., None]), axis=2)[..., None], axis=2)[
        ..., 0
    ]
    return np.abs(best - np.asarray(fix_m)) > separation_m


def epochs(tunnel: Tunnel, train: Train, rate_hz: float, head_range_m: tuple[float, float] | None = None):
    """Times [s] and head positions [m] while the whole train is inside the tunnel."""
    v = train.speed_kmh / 3.6
    lo, hi = head_range_m or (train.length_m, tunnel.length_m)
    n = int(math.floor((hi - lo) / v * rate_hz)) + 1
    t = np.arange(n) / rate_hz
    return t, lo + v * t


def snapshot_fixes(
    table,
    tunnel,
    cable,
    train,
    x_head,
    mm,
    propagation,
    measurement,
    shadow,
    rng,
    tones=None,
    bias_s: float = 0.0,
    delay_field=None,
    cols=None,
):
    """Per receiver snapshot measurements and fixes [epoch, receiver].

    ``fix`` is the snapshot position (separable: TDOA from the RSSI fix; wideband: the
    cable-ranging candidate chosen by :func:`resolve_ambiguity` from all receivers'
    measurements, the head starting in the first feed section; the tracker associates
    ``candidates`` with its own prediction); ``scale`` is each fix's relative
    standard deviation from its geometry (separable: the TDOA dilution; wideband: 1).
    Every receiver draws from its own child of ``rng``, so ``cols`` (the receivers to
    compute, default all) does not change any receiver's numbers.
    """
    x_rx = x_head[:, None] - train.receiver_offsets_m[None, :]
    n_e, k = x_rx.shape
    res = {
        n: np.full((n_e, k), np.nan)
        for n in ("fix", "fix_rssi", "sigma_tdoa", "gdop_seed", "gdop_tdoa", "tau", "scale")
    }
    res["candidates"] = None
    cands = []
    rngs = rng.spawn(k)
    for j in range(k) if cols is None else cols:
        if measurement == "separable":
            meas = separable_measurements(
                table, tunnel, cable, x_rx[:, j], shadow, rngs[j], mm, propagation, delay_field
            )
            xr_, xt, st, gs, gt = separable_fix(meas, table, tunnel, mm)
            res["fix"][:, j], res["fix_rssi"][:, j], res["sigma_tdoa"][:, j] = xt, xr_, st
            res["gdop_seed"][:, j], res["gdop_tdoa"][:, j] = gs, gt
            res["scale"][:, j] = gt
        elif measurement == "wideband":
            tau = wideband_delays(table, tunnel, cable, x_rx[:, j], rngs[j], wideband_view(table, mm), tones=tones)
            c = wideband_candidates(tau, tunnel, cable, bias_s)
            cands.append(c)
            res["tau"][:, j] = tau
            res["scale"][:, j] = 1.0
        else:
            raise ValueError(f"measurement must be one of {MEASUREMENTS}, got {measurement!r}")
    if cands:
        res["candidates"] = np.stack(cands, axis=1)  # [epoch, receiver, candidate]
        if cols is not None and len(cols) != k:
            raise ValueError("the wideband ambiguity is resolved with all receivers: cols must be None")
        res["head"], res["fix"] = resolve_ambiguity(
            res["candidates"],
            train.receiver_offsets_m,
            cable.feed_spacing_m,
            (0.0, cable.feed_spacing_m),
            tunnel.slot_spacing_m,
        )
        res["ambiguity_wrong"] = ambiguity_wrong(res["candidates"], res["fix"], x_rx, tunnel.slot_spacing_m)
    return x_rx, res


def environment(seed: int, which: str, realization: int, tunnel: Tunnel, mm: MeasurementModel):
    """The place's shadowing field and delay-error field (None if white) of one Monte Carlo
    realization; ``which`` is 'evaluation' or 'calibration'.  The same for every train."""
    n_sl = tunnel.slot_x_m.size
    shadow = shadow_field(
        make_rng(seed, spawn_key("tunnel", SHADOW_KEY[which], realization)),
        n_sl,
        tunnel.length_m,
        mm.shadow_sigma_db,
        mm.shadow_corr_m,
    )
    delay = delay_error_field(
        make_rng(seed, spawn_key("tunnel", DELAY_KEY[which], realization)), n_sl, tunnel.length_m, mm
    )
    return shadow, delay


def _noise_rng(seed: int, train: Train, propagation: str, measurement: str, realization: int):
    return make_rng(
        seed,
        spawn_key("tunnel", 200, TRAIN_IDS.get(train.name, 9), VARIANT_IDS[(propagation, measurement)], realization),
    )


def calibrate_separable(table, tunnel, cable, train, mm, propagation, tracking, seed) -> float:
    """r0 of a separable receiver from its calibration run (see :func:`run_train`) [m^2]."""
    vid = VARIANT_IDS[(propagation, "separable")]
    lo = train.length_m
    _, xh_cal = epochs(tunnel, train, tracking["rate_hz"], (lo, min(tunnel.length_m, lo + tracking["calibration_m"])))
    shadow, delay = environment(seed, "calibration", 0, tunnel, mm)
    rng_cal = make_rng(seed, spawn_key("tunnel", 300, TRAIN_IDS.get(train.name, 9), vid))
    xrx_cal, cal = snapshot_fixes(
        table, tunnel, cable, train, xh_cal, mm, propagation, "separable", shadow, rng_cal, delay_field=delay
    )
    return robust_variance(((cal["fix"] - xrx_cal) / cal["scale"]).ravel())


def kf_realizations(
    table, tunnel, cable, train, mm, propagation, tracking, seed, r0: float, realizations
) -> tuple[np.ndarray, np.ndarray]:
    """Head and tail errors of the head and tail receivers' KF [realization, epoch] [m] for
    the given Monte Carlo realizations of a separable receiver (each its own shadowing,
    delay-error field and noise); the vectorized KF, equal to :func:`kf_track`."""
    t, x_head = epochs(tunnel, train, tracking["rate_hz"])
    k = train.n_receivers
    ends = (0, k - 1)
    z, r_t, truth = [], [], []
    for r in realizations:
        shadow, delay = environment(seed, "evaluation", r, tunnel, mm)
        x_rx, res = snapshot_fixes(
            table,
            tunnel,
            cable,
            train,
            x_head,
            mm,
            propagation,
            "separable",
            shadow,
            _noise_rng(seed, train, propagation, "separable", r),
            delay_field=delay,
            cols=ends,
        )
        for j in ends:
            z.append(res["fix"][:, j])
            r_t.append(r0 * res["scale"][:, j] ** 2)
            truth.append(x_rx[:, j])
    z, r_t, truth = np.stack(z, 1), np.stack(r_t, 1), np.stack(truth, 1)
    est = kf_track_batch(
        z,
        r_t,
        1.0 / tracking["rate_hz"],
        tracking["accel_sigma_m_s2"],
        z[0],
        (r_t[0], tracking["max_speed_m_s"] ** 2),
        start_at_first=True,
    )  # start: the first fix
    err = np.abs(est - truth)
    return err[:, 0::2].T, err[:, 1::2].T


def run_train(
    table: xr.Dataset,
    tunnel: Tunnel,
    cable: Cable,
    train: Train,
    mm: MeasurementModel,
    propagation: str,
    measurement: str,
    tracking: dict,
    seed: int,
    realizations: int = 1,
) -> xr.Dataset:
    """Calibration run, then the evaluation run: snapshot fixes, KF on the head and on
    the tail receiver, rigid-train KF on all receivers, PF on head and tail; errors.

    The calibration run (another tunnel realization of the shadowing, its own noise, the
    first ``calibration_m`` of travel) sets the measurement variance: R_t = r0 s_t^2 with
    s_t the fix's geometric dilution and r0 the robust variance of error / s on that run;
    for the wideband receiver also the median delay bias of its peak.  The calibration run
    is a survey with known positions (its wideband fixes take the candidate nearest the
    truth); nothing is taken from the evaluation run, whose filters start from its first
    snapshot fix and whose ambiguity is resolved from its measurements.

    Realization 0 is the full run (filterpy KF, rigid KF, PF); for a separable receiver,
    realizations 1 .. R-1 repeat the head and tail KF with their own shadowing,
    delay-error field and noise (:func:`kf_realizations`): ``rep_err*`` [realization,
    epoch] hold all R for the pooled key numbers and their Monte Carlo spread.
    """
    if realizations < 1:
        raise ValueError(f"realizations must be >= 1, got {realizations!r}")
    vid = VARIANT_IDS[(propagation, measurement)]
    tid = TRAIN_IDS.get(train.name, 9)
    dt = 1.0 / tracking["rate_hz"]
    shadow_cal, delay_cal = environment(seed, "calibration", 0, tunnel, mm)
    shadow_eval, delay_eval = environment(seed, "evaluation", 0, tunnel, mm)
    tones = tone_response(table, mm) if measurement == "wideband" else None
    lo = train.length_m
    _, xh_cal = epochs(tunnel, train, tracking["rate_hz"], (lo, min(tunnel.length_m, lo + tracking["calibration_m"])))
    rng_cal = make_rng(seed, spawn_key("tunnel", 300, tid, vid))
    xrx_cal, cal = snapshot_fixes(
        table,
        tunnel,
        cable,
        train,
        xh_cal,
        mm,
        propagation,
        measurement,
        shadow_cal,
        rng_cal,
        tones,
        delay_field=delay_cal,
    )
    bias_s = 0.0
    if measurement == "wideband":
        bias_s = float(np.median(cal["tau"] - cable_model_delay_s(xrx_cal, tunnel, cable)))
        cal["fix"] = np.stack(
            [
                wideband_candidates(cal["tau"][:, j], tunnel, cable, bias_s)[
                    np.arange(xrx_cal.shape[0]),
                    np.argmin(
                        np.abs(wideband_candidates(cal["tau"][:, j], tunnel, cable, bias_s) - xrx_cal[:, j : j + 1]),
                        axis=1,
                    ),
                ]
                for j in range(xrx_cal.shape[1])
            ],
            axis=1,
        )
    r0 = robust_variance(((cal["fix"] - xrx_cal) / cal["scale"]).ravel())
    t, x_head = epochs(tunnel, train, tracking["rate_hz"])
    x_rx, res = snapshot_fixes(
        table,
        tunnel,
        cable,
        train,
        x_head,
        mm,
        propagation,
        measurement,
        shadow_eval,
        _noise_rng(seed, train, propagation, measurement, 0),
        tones,
        bias_s,
        delay_field=delay_eval,
    )
    meas = res["candidates"] if res["candidates"] is not None else res["fix"][..., None]
    r_t = r0 * res["scale"] ** 2
    q = tracking["accel_sigma_m_s2"]
    vmax = tracking["max_speed_m_s"]
    offs = train.receiver_offsets_m
    k = x_rx.shape[1]
    ends = (0, k - 1)
    kf = np.empty((t.size, 2))
    kf_var = np.empty((t.size, 2))
    nis = np.empty((t.size, 2))
    # every filter starts from the first snapshot fix with its variance (not the truth)
    z0, p0 = res["fix"][0], r_t[0]
    for c, j in enumerate(ends):
        kf[:, c], _, kf_var[:, c], nis[:, c] = kf_track(
            meas[:, j : j + 1], r_t[:, j : j + 1], dt, q, (z0[j], 0.0), (p0[j], vmax**2), start_at_first=True
        )
    w0 = 1.0 / p0  # rigid train: the precision-weighted head from all receivers' first fixes
    rigid, _, rigid_var, _ = kf_track(
        meas,
        r_t,
        dt,
        q,
        (float(np.sum(w0 * (z0 + offs)) / np.sum(w0)), 0.0),
        (float(1.0 / np.sum(w0)), vmax**2),
        offsets_m=offs,
        start_at_first=True,
    )
    rng_pf = make_rng(seed, spawn_key("tunnel", 400, tid, vid))
    pf = np.empty((t.size, 2))
    for c, j in enumerate(ends):
        pf[:, c], _ = pf_track(
            meas[:, j],
            r_t[:, j],
            dt,
            q,
            (z0[j], 0.0),
            (p0[j], vmax**2),
            tracking["n_particles"],
            rng_pf,
            start_at_first=True,
        )
    head, tail = x_head, x_head - train.length_m
    m = {"units": "m"}
    tr = ("time_s", "receiver")
    ds = xr.Dataset(
        {
            "x_head_true": ("time_s", x_head, {**m, "long_name": "true head position"}),
            "x_rx_true": (tr, x_rx, {**m, "long_name": "true receiver position"}),
            "snapshot": (tr, res["fix"], {**m, "long_name": f"snapshot fix ({measurement})"}),
            "snapshot_rssi": (tr, res["fix_rssi"], {**m, "long_name": "RSSI-ranging LS fix (separable only)"}),
            "sigma_tdoa": (tr, res["sigma_tdoa"], {**m, "long_name": "TDOA fix standard deviation from its geometry"}),
            "gdop_seed": (
                tr,
                res["gdop_seed"],
                {"units": "1", "long_name": "GDOP, the seed's 2-D formula (seed 4.1.1)"},
            ),
            "gdop_tdoa": (
                tr,
                res["gdop_tdoa"],
                {"units": "1", "long_name": "along-track TDOA dilution (sigma_x / c sigma_tau)"},
            ),
            "wideband_delay": (tr, res["tau"], {"units": "s", "long_name": "CIR peak delay (wideband only)"}),
            "wideband_delay_error": (
                tr,
                res["tau"] - bias_s - cable_model_delay_s(x_rx, tunnel, cable),
                {
                    "units": "s",
                    "long_name": "CIR peak delay minus the calibrated cable-point "
                    "model delay at the true position (wideband only): the channel's delay error",
                },
            ),
            "kf_head": ("time_s", kf[:, 0], {**m, "long_name": "Kalman-filtered head position (head receiver)"}),
            "kf_tail": ("time_s", kf[:, 1], {**m, "long_name": "Kalman-filtered tail position (tail receiver)"}),
            "kf_head_var": ("time_s", kf_var[:, 0], {"units": "m2", "long_name": "KF head position variance"}),
            "kf_head_nis": ("time_s", nis[:, 0], {"units": "1", "long_name": "KF head normalized innovation squared"}),
            "rigid_head": ("time_s", rigid, {**m, "long_name": "rigid-train KF head position (all receivers)"}),
            "rigid_tail": ("time_s", rigid - train.length_m, {**m, "long_name": "rigid-train KF tail position"}),
            "pf_head": ("time_s", pf[:, 0], {**m, "long_name": "particle-filter head position"}),
            "pf_tail": ("time_s", pf[:, 1], {**m, "long_name": "particle-filter tail position"}),
        },
        coords={
            "time_s": ("time_s", t, {"units": "s", "long_name": "time since the tail entered"}),
            "receiver": ("receiver", np.arange(k), {"units": "1", "long_name": "receiver index from the head"}),
            "receiver_offset_m": ("receiver", offs, {**m, "long_name": "receiver distance behind the head"}),
        },
        attrs={
            "train": train.name,
            "length_m": train.length_m,
            "speed_kmh": train.speed_kmh,
            "propagation": propagation,
            "measurement": measurement,
            "r0_m2": r0,
            "wideband_bias_s": bias_s,
        },
    )
    for est in ("kf", "rigid", "pf"):
        eh = np.abs(ds[f"{est}_head"].values - head)
        et = np.abs(ds[f"{est}_tail"].values - tail)
        ds[f"{est}_err_head"] = ("time_s", eh, {**m, "long_name": f"{est} head error"})
        ds[f"{est}_err_tail"] = ("time_s", et, {**m, "long_name": f"{est} tail error"})
        ds[f"{est}_err"] = (
            "time_s",
            np.sqrt((eh**2 + et**2) / 2.0),
            {**m, "long_name": f"{est} train error sqrt((e_head^2 + e_tail^2)/2) (seed 4.4.3)"},
        )
    rep_h, rep_t = ds["kf_err_head"].values[None, :], ds["kf_err_tail"].values[None, :]
    if measurement == "separable" and realizations > 1:
        eh, et = kf_realizations(
            table, tunnel, cable, train, mm, propagation, tracking, seed, r0, range(1, realizations)
        )
        rep_h, rep_t = np.concatenate([rep_h, eh]), np.concatenate([rep_t, et])
    rt = ("realization", "time_s")
    ds = ds.assign_coords(
        realization=("realization", np.arange(rep_h.shape[0]), {"units": "1", "long_name": "Monte Carlo realization"})
    )
    ds["rep_err_head"] = (rt, rep_h, {**m, "long_name": "KF head error per realization"})
    ds["rep_err_tail"] = (rt, rep_t, {**m, "long_name": "KF tail error per realization"})
    ds["rep_err"] = (rt, np.sqrt((rep_h**2 + rep_t**2) / 2.0), {**m, "long_name": "KF train error per realization"})
    if measurement == "wideband":
        ds["ambiguity_wrong"] = (
            tr,
            res["ambiguity_wrong"].astype(np.int8),
            {"units": "1", "long_name": "1 where the snapshot fix took the wrong side of the feed (or feed)"},
        )
    ds["snapshot_err"] = (tr, np.abs(res["fix"] - x_rx), {**m, "long_name": "snapshot error"})
    ds["snapshot_rssi_err"] = (tr, np.abs(res["fix_rssi"] - x_rx), {**m, "long_name": "RSSI-LS snapshot error"})
    return ds
