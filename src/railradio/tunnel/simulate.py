"""A train crossing the tunnel: measurements, snapshot fixes, tracks (source 003 §3.3, §7.2).

Measurement models (docs/model/tunnel.md §3, both reported):

* ``separable`` - the source's assumption that every slot's RSSI and delay are measured on
  their own [source 4.2, 6.2]: per slot the coherent one-slot power of the channel table
  (its own multipath fading) plus log-normal shadowing (a spatial field per slot along the
  tunnel, correlated over ``shadow_corr_m``, the same for every train: it belongs to the
  place), and the line-of-sight delay plus Gaussian error; the ``n_slots`` strongest
  measured slots within ``window_m`` are used.  Fix: RSSI ranging + linearized LS, then
  TDOA Gauss-Newton from it.  The delay error is ``white`` (independent per epoch and
  slot, the source's assumption, which a 20 Hz filter averages away), ``ar1`` (per slot an
  AR(1) field along the track, correlated over ``delay_corr_m``: a multipath bias that
  changes with position) or ``slot_bias`` (per slot one constant bias: a calibration error
  of the slot's delay); same sigma in all three.
* ``wideband`` - what a receiver of bandwidth B actually sees: the sum of all slots'
  rays (every slot of the table, :func:`railradio.tunnel.wideband.wideband_view`), each
  slot's carrying the place's shadowing, with
  their cable delays (velocity factor v), sampled on ``n_tones`` tones across
  B with thermal noise, transformed to a channel impulse response; its strongest peak
  gives a delay that maps to the cable distance from the feed, x = x_feed +- v c (tau - h/c).
  The +- is resolved from the measurements
  (:func:`railradio.tunnel.wideband.resolve_ambiguity`: the K receivers sit
  at known offsets along the train, and on the two sides of a feed their delays run in
  opposite directions); which feed (the cable is periodic, no measurement can tell) by
  continuity from the tunnel entry (the head is in the first feed section when the whole
  train has entered), never from the truth.

Every filter starts from the first snapshot fix with its variance (speed 0 +- the maximum
speed), not from the true position.

The train: K receivers evenly along its length [source 3.3.1], constant speed, whole train
inside the tunnel; epochs at ``rate_hz``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import xarray as xr

from railradio.rng import make_rng, spawn_key
from railradio.tunnel.filters import track_fixes
from railradio.tunnel.geometry import Cable, Tunnel
from railradio.tunnel.measurement import MeasurementModel, delay_error_field, shadow_field
from railradio.tunnel.run_data import add_errors, add_snapshot_errors, run_dataset, with_realizations
from railradio.tunnel.separable import separable_fix, separable_measurements
from railradio.tunnel.tracking import kf_track_batch, robust_variance
from railradio.tunnel.wideband import cable_model_delay_s, tone_response, wideband_candidates
from railradio.tunnel.wideband_runs import CableModelError, wideband_fixes, wideband_kf_errors

TRAIN_IDS = {"metro": 1, "hst": 2, "freight": 3}
"""Train type -> its number in the random-stream keys (``spawn_key('tunnel', ...)``; another name: 9)."""
MEASUREMENTS = ("separable", "wideband")
PROPAGATION_MEASUREMENT_IDS = {
    ("physical", "separable"): 1,
    ("physical", "wideband"): 2,
    ("source", "separable"): 3,
    ("source", "wideband"): 4,
}
"""(propagation, measurement) -> its number in the random-stream keys (``spawn_key('tunnel', ...)``)."""
SHADOW_KEY = {"evaluation": 100, "calibration": 101}
DELAY_KEY = {"evaluation": 102, "calibration": 103}
FEED_KEY = 104
"""Random-stream key of the feeds' delay calibration errors (:class:`CableModelError`), per realization."""


@dataclass(frozen=True)
class Train:
    """A train type crossing the tunnel at constant speed with receivers along its length.

    Parameters
    ----------
    name : str
        Train type (``metro``, ``hst``, ``freight``; keys :data:`TRAIN_IDS`).
    length_m : float
        Train length L, head to tail [m]; positive.
    speed_kmh : float
        Constant speed [km/h]; positive.
    n_receivers : int
        Number K of receivers evenly along the train, the first at the head and the last
        at the tail; >= 2.

    Raises
    ------
    ValueError
        When ``n_receivers`` < 2 or ``length_m`` or ``speed_kmh`` is not positive.
    """

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
        """Receiver k at x_head - k L / (K - 1) [source 3.3.1]."""
        return np.arange(self.n_receivers) * self.length_m / (self.n_receivers - 1)


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
    cable-ranging candidate chosen by :func:`railradio.tunnel.wideband.resolve_ambiguity` from all receivers'
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
        for n in ("fix", "fix_rssi", "sigma_tdoa", "gdop_source", "gdop_tdoa", "tau", "scale")
    }
    if measurement == "wideband":
        if cols is not None and len(cols) != k:
            raise ValueError("the wideband ambiguity is resolved with all receivers: cols must be None")
        offs = train.receiver_offsets_m
        res.update(wideband_fixes(table, tunnel, cable, offs, x_rx, mm, [shadow], [rng], tones, bias_s)[0])
        return x_rx, res
    if measurement != "separable":
        raise ValueError(f"measurement must be one of {MEASUREMENTS}, got {measurement!r}")
    res["candidates"] = None
    rngs = rng.spawn(k)
    for j in range(k) if cols is None else cols:
        meas = separable_measurements(table, tunnel, cable, x_rx[:, j], shadow, rngs[j], mm, propagation, delay_field)
        xr_, xt, st, gs, gt = separable_fix(meas, table, tunnel, mm)
        res["fix"][:, j], res["fix_rssi"][:, j], res["sigma_tdoa"][:, j] = xt, xr_, st
        res["gdop_source"][:, j], res["gdop_tdoa"][:, j] = gs, gt
        res["scale"][:, j] = gt
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
        spawn_key(
            "tunnel",
            200,
            TRAIN_IDS.get(train.name, 9),
            PROPAGATION_MEASUREMENT_IDS[(propagation, measurement)],
            realization,
        ),
    )


def calibrate_separable(table, tunnel, cable, train, mm, propagation, tracking, seed) -> float:
    """r0 of a separable receiver from its calibration run (see :func:`run_train`) [m^2]."""
    return _calibrate(table, tunnel, cable, train, mm, propagation, "separable", tracking, seed, None).r0_m2


def kf_realizations(
    table, tunnel, cable, train, mm, propagation, tracking, seed, r0: float, realizations
) -> tuple[np.ndarray, np.ndarray]:
    """Head and tail errors of the head and tail receivers' KF [realization, epoch] [m] for
    the given Monte Carlo realizations of a separable receiver (each its own shadowing,
    delay-error field and noise); the vectorized KF, equal to :func:`railradio.tunnel.tracking.kf_track`.

    Parameters
    ----------
    table : xarray.Dataset
        Tabulated slot-to-receiver channel of the run's propagation.
    tunnel : Tunnel
        The tunnel of the table's cross-section.
    cable : Cable
        The leaky cable.
    train : Train
        The train type crossing the tunnel.
    mm : MeasurementModel
        The receivers' measurement model.
    propagation : {'physical', 'source'}
        The table's propagation model (selects the random streams).
    tracking : dict
        The ``tracking`` section: ``rate_hz`` [Hz], ``accel_sigma_m_s2`` [m/s^2], ``max_speed_m_s`` [m/s].
    seed : int
        Root seed of the workflow.
    r0 : float
        Measurement variance per unit dilution squared (:func:`calibrate_separable`) [m^2].
    realizations : iterable of int
        Monte Carlo realizations (0: the fields and noise of :func:`run_train`'s evaluation run).

    Returns
    -------
    tuple of numpy.ndarray
        ``(err_head, err_tail)``, each [realization, epoch]: |KF - truth| of the head and tail receiver [m].
    """
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
    cable_error: CableModelError | None = None,
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

    Realization 0 is the full run (filterpy KF, rigid KF, PF); realizations 1 .. R-1 repeat
    the head and tail KF with their own shadowing, delay-error field and noise (separable:
    :func:`kf_realizations`; wideband: :func:`railradio.tunnel.wideband_runs.wideband_kf_errors`,
    all realizations synthesized together): ``rep_err*`` [realization, epoch] hold all R
    for the pooled key numbers and their Monte Carlo spread.

    Parameters
    ----------
    table : xarray.Dataset
        Tabulated slot-to-receiver channel (:func:`railradio.tunnel.study.make_table`) of
        the run's propagation.
    tunnel : Tunnel
        The tunnel of the table's cross-section.
    cable : Cable
        The leaky cable.
    train : Train
        The train type crossing the tunnel.
    mm : MeasurementModel
        The receivers' measurement model (:mod:`railradio.tunnel.measurement`).
    propagation : {'physical', 'source'}
        The table's propagation model (selects the random streams).
    measurement : {'separable', 'wideband'}
        The receiver's measurement model (module docstring).
    tracking : dict
        The ``tracking`` section of the configuration: ``rate_hz`` (epoch rate) [Hz],
        ``accel_sigma_m_s2`` (white-acceleration process noise) [m/s^2],
        ``max_speed_m_s`` (initial speed uncertainty) [m/s], ``n_particles`` (particle
        filter), ``calibration_m`` (travel of the calibration run) [m].
    seed : int
        Root seed of the workflow.
    realizations : int
        Number R of Monte Carlo realizations; >= 1 (more than 1 only adds KF runs).
    cable_error : CableModelError or None
        How the wideband receiver's cable model differs from the installed cable (the
        feeds' errors drawn per realization, the same for every train: they belong to the
        place); None: no error.  The calibration run's model is exact.

    Returns
    -------
    xarray.Dataset
        Dims ``time_s`` (time since the tail entered [s]), ``receiver`` (index from the
        head, with ``receiver_offset_m`` behind the head [m]) and ``realization``.  Main
        variables [m] unless stated: ``x_head_true`` [time_s], ``x_rx_true``, ``snapshot``,
        ``snapshot_rssi``, ``sigma_tdoa``, ``gdop_source`` [1], ``gdop_tdoa`` [1],
        ``wideband_delay`` [s], ``wideband_delay_error`` [s], ``snapshot_err``,
        ``snapshot_rssi_err`` [time_s, receiver]; the tracks ``kf_head``, ``kf_tail``,
        ``kf_head_var`` [m^2], ``kf_head_nis`` [1], ``rigid_head``, ``rigid_tail``,
        ``pf_head``, ``pf_tail`` and their errors ``{kf,rigid,pf}_err_head``,
        ``{kf,rigid,pf}_err_tail``, ``{kf,rigid,pf}_err`` (train error) [time_s];
        ``rep_err_head``, ``rep_err_tail``, ``rep_err`` [realization, time_s]; wideband:
        ``ambiguity_wrong`` [time_s, receiver] [1].  Attributes: ``train``, ``length_m``,
        ``speed_kmh``, ``propagation``, ``measurement``, ``r0_m2`` [m^2],
        ``wideband_bias_s`` [s].

    Raises
    ------
    ValueError
        When ``realizations`` < 1.
    KeyError
        When (``propagation``, ``measurement``) is not a key of :data:`PROPAGATION_MEASUREMENT_IDS`.
    """
    if realizations < 1:
        raise ValueError(f"realizations must be >= 1, got {realizations!r}")
    pm_id = PROPAGATION_MEASUREMENT_IDS[(propagation, measurement)]
    tid = TRAIN_IDS.get(train.name, 9)
    tones = tone_response(table, mm) if measurement == "wideband" else None
    cal = _calibrate(table, tunnel, cable, train, mm, propagation, measurement, tracking, seed, tones)
    ev, reps = _evaluate(
        table,
        tunnel,
        cable,
        train,
        mm,
        (propagation, measurement),
        tracking,
        seed,
        tones,
        cal.bias_s,
        realizations,
        cable_error,
    )
    tracks = track_fixes(
        ev.res, cal.r0_m2, tracking, train.receiver_offsets_m, make_rng(seed, spawn_key("tunnel", 400, tid, pm_id))
    )
    ds = run_dataset(ev, tracks, cal, tunnel, cable, train, propagation, measurement)
    add_errors(ds, ev.x_head, train.length_m)
    rep_h, rep_t = ds["kf_err_head"].values[None, :], ds["kf_err_tail"].values[None, :]
    if measurement == "separable" and realizations > 1:
        eh, et = kf_realizations(
            table, tunnel, cable, train, mm, propagation, tracking, seed, cal.r0_m2, range(1, realizations)
        )
        rep_h, rep_t = np.concatenate([rep_h, eh]), np.concatenate([rep_t, et])
    rep_rigid = None
    if measurement == "wideband":
        rep_rigid = ds["rigid_err"].values[None, :]
    if reps:
        eh, et, er = wideband_kf_errors(reps, ev.x_rx, cal.r0_m2, tracking, train.receiver_offsets_m)
        rep_h, rep_t = np.concatenate([rep_h, eh]), np.concatenate([rep_t, et])
        rep_rigid = np.concatenate([rep_rigid, er])
    ds = with_realizations(ds, rep_h, rep_t, rep_rigid)
    add_snapshot_errors(ds, ev, measurement)
    return ds


class _Calibration(NamedTuple):
    """What the calibration run of :func:`run_train` sets."""

    r0_m2: float
    """robust variance of the fix error over its geometric dilution"""
    bias_s: float
    """median delay bias of the wideband receiver's peak (0 for the separable receiver)"""


def _calibrate(table, tunnel, cable, train, mm, propagation, measurement, tracking, seed, tones) -> _Calibration:
    """The calibration run of :func:`run_train`: a survey with known positions over the first
    ``calibration_m`` of travel (its wideband fixes take the candidate nearest the truth)."""
    pm_id = PROPAGATION_MEASUREMENT_IDS[(propagation, measurement)]
    tid = TRAIN_IDS.get(train.name, 9)
    shadow_cal, delay_cal = environment(seed, "calibration", 0, tunnel, mm)
    lo = train.length_m
    _, xh_cal = epochs(tunnel, train, tracking["rate_hz"], (lo, min(tunnel.length_m, lo + tracking["calibration_m"])))
    rng_cal = make_rng(seed, spawn_key("tunnel", 300, tid, pm_id))
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
    return _Calibration(r0, bias_s)


class _Evaluation(NamedTuple):
    """The evaluation run of :func:`run_train` (realization 0): times [s], true head [epoch]
    and receiver positions [epoch, receiver] [m], the snapshot fixes of :func:`snapshot_fixes`."""

    t: np.ndarray
    x_head: np.ndarray
    x_rx: np.ndarray
    res: dict


def _evaluate(
    table,
    tunnel,
    cable,
    train,
    mm,
    setup,
    tracking,
    seed,
    tones,
    bias_s: float,
    realizations: int = 1,
    cable_error=None,
) -> tuple[_Evaluation, list[dict]]:
    """Every receiver's snapshot fixes on the evaluation run (its own shadowing, delay-error
    field and noise; the wideband ambiguity resolved from its measurements); for the wideband
    receiver also realizations 1 .. R-1 (synthesized with realization 0), else none."""
    propagation, measurement = setup
    t, x_head = epochs(tunnel, train, tracking["rate_hz"])
    if measurement != "wideband":
        shadow_eval, delay_eval = environment(seed, "evaluation", 0, tunnel, mm)
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
        return _Evaluation(t, x_head, x_rx, res), []
    x_rx = x_head[:, None] - train.receiver_offsets_m[None, :]
    n_feeds = cable.feed_x_m(tunnel.length_m).size
    models = None
    if cable_error is not None:
        models = [
            cable_error.receiver_model(cable, n_feeds, make_rng(seed, spawn_key("tunnel", FEED_KEY, r)))
            for r in range(realizations)
        ]
    res_all = wideband_fixes(
        table,
        tunnel,
        cable,
        train.receiver_offsets_m,
        x_rx,
        mm,
        [environment(seed, "evaluation", r, tunnel, mm)[0] for r in range(realizations)],
        [_noise_rng(seed, train, propagation, measurement, r) for r in range(realizations)],
        tones,
        bias_s,
        models,
    )
    res = {n: np.full(x_rx.shape, np.nan) for n in ("fix_rssi", "sigma_tdoa", "gdop_source", "gdop_tdoa")}
    return _Evaluation(t, x_head, x_rx, res | res_all[0]), res_all[1:]
