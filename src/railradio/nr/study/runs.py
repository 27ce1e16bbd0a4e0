"""The nr run's steps between the shards and the tracks, as the workflow's rules call them.

:func:`read_shards` joins a realization's shards; :func:`case_estimates` cuts a sensitivity
case's estimates to its epochs and adds its clock errors; :func:`calibrate_receivers` calibrates
every receiver's trackers on a calibration run (docs/model/nr.md §6); :func:`track_receivers`
tracks one realization with them and :func:`track_imm` runs the EKF, the IMM and the RTS
smoother of one receiver; both score the tracks against the truth (scoring only: the
trackers see the estimates, the deployment and their calibration).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

from railradio.io import read_dataset
from railradio.nr.channel.clocks import apply_clock_errors
from railradio.nr.engine.simulate import Scenario
from railradio.nr.tracking.bounds import change_epochs
from railradio.nr.tracking.calibration import calibrate, measurement_errors
from railradio.nr.tracking.dynamics import process_noise, transition
from railradio.nr.tracking.ekf import TrackerConfig, nees_position
from railradio.nr.tracking.imm import ImmConfig, position_nees, q_for_jump, track_filters
from railradio.nr.tracking.measurement import MEASUREMENT_SETS
from railradio.nr.tracking.smoother import rts_smooth
from railradio.nr.tracking.track import track
from railradio.rng import spawn_key

GATES = (False, True)  # each tracker runs without and with the χ² innovation gate


def read_shards(paths: Sequence[str]) -> xr.Dataset:
    """One realization's estimate shards joined along ``epoch``: the per-epoch variables are
    concatenated; the others (the train's geometry) are the same in every shard.

    Parameters
    ----------
    paths : sequence of str
        Paths of the shards' netCDF files, in epoch order.

    Returns
    -------
    xarray.Dataset
        The realization's :func:`railradio.nr.engine.epochs.simulate_epochs` dataset over all the
        shards' epochs.
    """
    return xr.concat(
        [read_dataset(p) for p in paths], dim="epoch", data_vars="minimal", coords="minimal", compat="override"
    )


def case_estimates(ds: xr.Dataset, n_epochs: int, seed: int, rid: int, sync: dict[str, Any]) -> xr.Dataset:
    """A sensitivity case's estimates: the first ``n_epochs`` epochs of realization ID ``rid``
    (0: r0, 1000: the calibration run), with the clock errors of the case's ``nr.sync`` added
    to the measured TOAs (keyed by that realization).

    Parameters
    ----------
    ds : xarray.Dataset
        The realization's estimates (:func:`read_shards`).
    n_epochs : int
        Epochs the case keeps (the first ones).
    seed : int
        The config seed.
    rid : int
        Realization ID of ``ds`` (0: r0, 1000: the calibration run).
    sync : dict
        The case's ``nr.sync`` section: ``rrh_sigma_s`` (spread of the RRH clock offsets, s)
        and ``train_bias_s`` (the train clock's bias, s).

    Returns
    -------
    xarray.Dataset
        ``ds`` cut to ``n_epochs`` epochs with the clock errors added to ``toa_hat`` [s]
        (:func:`railradio.nr.channel.clocks.apply_clock_errors`).
    """
    return apply_clock_errors(
        ds.isel(epoch=slice(0, int(n_epochs))),
        int(seed),
        spawn_key("nr", rid),
        float(sync["rrh_sigma_s"]),
        float(sync["train_bias_s"]),
    )


def point_model(ds: xr.Dataset, tracker: dict[str, Any]) -> xr.Dataset:
    """The estimates as the tracker models them: without the panels' lever arm when
    ``tracker['lever_arm']`` is false (the point model).

    Parameters
    ----------
    ds : xarray.Dataset
        Estimates (:func:`read_shards`).
    tracker : dict
        The ``nr.tracker`` config section (uses ``lever_arm``, bool).

    Returns
    -------
    xarray.Dataset
        ``ds`` itself, or ``ds`` without ``train_panel_x`` (the panels' along-track positions, m).
    """
    return ds if tracker["lever_arm"] else ds.drop_vars("train_panel_x", errors="ignore")


def tracker_name(rx: str, measurements: str, gate: bool) -> str:
    """The calibration record's key of one tracker: ``receiver/measurements/gate|nogate``.

    Parameters
    ----------
    rx : str
        Receiver name.
    measurements : str
        Measurement set: ``aod``, ``toa`` or ``aod_toa``.
    gate : bool
        Whether the tracker runs with the χ² innovation gate.

    Returns
    -------
    str
        The key, e.g. ``"<rx>/aod_toa/gate"``.
    """
    return f"{rx}/{measurements}/{'gate' if gate else 'nogate'}"


def calibrate_receivers(
    ds: xr.Dataset,
    scn: Scenario,
    tracker: dict[str, Any],
    selection: dict[str, str],
    measurement_sets: Sequence[str],
    log,
) -> dict[str, dict]:
    """Noise levels and q of every receiver's trackers (each measurement set, gate off and on), each
    calibrated as it will run, with its q search: ``{tracker_name: record}``.

    Parameters
    ----------
    ds : xarray.Dataset
        The calibration run's estimates (all receivers, :func:`read_shards`).
    scn : Scenario
        The scenario the estimates were simulated with (deployment, ``trajectory.dt_s``).
    tracker : dict
        The ``nr.tracker`` config section (``q_grid`` [m² s⁻⁵], ``gate_prob`` (1),
        ``w_distance_edges_m`` [m], ``aod_angle_edges_deg`` [deg], ``lever_arm``).
    selection : dict of str to str
        Receiver name -> strength measure choosing its measured RRHs
        (:func:`railradio.nr.study.workflow.receiver_selection`).
    measurement_sets : sequence of str
        Measurement sets to calibrate (keys of :data:`railradio.nr.tracking.measurement.MEASUREMENT_SETS`:
        ``aod``, ``toa``, ``aod_toa``).
    log : logging.Logger
        Receives one line per tracker.

    Returns
    -------
    dict of str to dict
        :func:`tracker_name` -> calibration record: ``q`` [m² s⁻⁵], ``sigma_aod_rad`` [rad],
        ``sigma_toa_s`` [s], optional distance bins (:meth:`TrackerConfig.record`), and
        ``q_search`` (the q values tried and their costs).

    Raises
    ------
    ValueError
        From :func:`railradio.nr.tracking.calibration.calibrate` (empty ``q_grid``, bad calibrated values).
    """
    dep = scn.deployment
    out = {}
    for rx in ds["receiver"].values:
        dsr = ds.sel(receiver=rx)
        for measurements in measurement_sets:
            for gate in GATES:
                name = tracker_name(rx, measurements, gate)
                search = {}
                cfg = calibrate(
                    dsr,
                    measurements,
                    dep.x_m,
                    dep.offset_m,
                    dep.h_bs_m - dep.h_ut_m,
                    scn.trajectory.dt_s,
                    np.asarray(tracker["q_grid"]),
                    gate,
                    selection[str(rx)],
                    distance_edges_m=tuple(tracker["w_distance_edges_m"]),
                    gate_prob=float(tracker["gate_prob"]),
                    search=search,
                    aod_angle_edges_rad=tuple(np.radians(tracker["aod_angle_edges_deg"])),
                )
                out[name] = cfg.record() | {"q_search": search}
                log.info("%s: %s", name, out[name])
    return out


def track_receivers(
    ds: xr.Dataset,
    scn: Scenario,
    cal: dict[str, dict],
    tracker: dict[str, Any],
    selection: dict[str, str],
    measurement_sets: Sequence[str],
    log,
) -> xr.Dataset:
    """Every receiver's trackers on one realization, scored: 2-D EKF and snapshot position
    errors, NIS and position NEES per dimension, the measured RRHs' AOD and range errors.

    Parameters
    ----------
    ds : xarray.Dataset
        One realization's estimates (all receivers).
    scn : Scenario
        The scenario (deployment, ``trajectory.dt_s``).
    cal : dict of str to dict
        Calibration records by :func:`tracker_name` (:func:`calibrate_receivers`).
    tracker : dict
        The ``nr.tracker`` config section (uses ``gate_prob``).
    selection : dict of str to str
        Receiver name -> strength measure of its measured RRHs.
    measurement_sets : sequence of str
        Measurement sets to run (``aod``, ``toa``, ``aod_toa``).
    log : logging.Logger
        Receives each tracker's mean error.

    Returns
    -------
    xarray.Dataset
        ``pos_err`` [m] (2-D EKF position error), ``nis`` and ``nees`` [1] (per dimension), dims
        (``receiver``, ``measurements``, ``gate``, ``epoch``); ``snap_err`` [m] (snapshot LS error),
        dims (``receiver``, ``measurements``, ``epoch``); ``aod_err`` [rad] and ``range_err`` [m] of the
        measured RRHs, dims (``receiver``, ``epoch``, ``slot``); ``t`` [s], ``x_true`` [m],
        ``a_true`` [m/s²], ``sir_best`` [dB] per ``epoch``.

    Raises
    ------
    KeyError
        When ``cal`` lacks a receiver/measurements/gate combination.
    """
    dep = scn.deployment
    receivers = [str(r) for r in ds["receiver"].values]
    measurement_sets = [str(v) for v in measurement_sets]
    n = ds.sizes["epoch"]
    err = np.full((len(receivers), len(measurement_sets), 2, n), np.nan)
    along = np.full((len(receivers), len(measurement_sets), 2, n), np.nan)
    nis = np.full((len(receivers), len(measurement_sets), 2, n), np.nan)
    nees = np.full((len(receivers), len(measurement_sets), 2, n), np.nan)
    snap = np.full((len(receivers), len(measurement_sets), n), np.nan)
    meas_aod = np.full((len(receivers), n, 3), np.nan)
    meas_rng = np.full((len(receivers), n, 3), np.nan)
    x_true = ds["x_true"].values
    for i, rx in enumerate(receivers):
        dsr = ds.sel(receiver=rx)
        meas_aod[i], meas_rng[i] = measurement_errors(dsr, selection[str(rx)], flat=False)
        for j, measurements in enumerate(measurement_sets):
            for g, gate in enumerate(GATES):
                c = cal[tracker_name(rx, measurements, gate)]
                cfg = TrackerConfig.from_record(c, measurements=measurements, gate=gate, gate_prob=tracker["gate_prob"])
                out = track(
                    dsr,
                    dep.x_m,
                    dep.offset_m,
                    dep.h_bs_m - dep.h_ut_m,
                    scn.trajectory.dt_s,
                    cfg,
                    strength=selection[str(rx)],
                    snapshot=(g == 0),
                )
                along[i, j, g] = out["state"][:, 0] - x_true  # scoring only (the track: y = 0)
                err[i, j, g] = np.hypot(along[i, j, g], out["state"][:, 1])
                upd = out["n_used"] > 0
                nis[i, j, g, upd] = out["nis"][upd] / (sum(MEASUREMENT_SETS[measurements]) * out["n_used"][upd])
                nees[i, j, g] = nees_position(out["state"], out["cov"], x_true) / 2  # scoring only
                if g == 0:
                    snap[i, j] = np.hypot(out["snapshot"][:, 0] - x_true, out["snapshot"][:, 1])
                log.info("%s %s gate=%s: mean error %.3f m", rx, measurements, gate, np.nanmean(err[i, j, g]))
    return _track_dataset(ds, receivers, measurement_sets, err, along, nis, nees, snap, meas_aod, meas_rng)


def _track_dataset(ds, receivers, measurement_sets, err, along, nis, nees, snap, meas_aod, meas_rng) -> xr.Dataset:
    """The tracks' scores as a Dataset (results/nr/track/{real}.nc)."""
    dims = ("receiver", "measurements", "gate", "epoch")
    return xr.Dataset(
        {
            "pos_err": (dims, err, {"units": "m", "long_name": "2-D EKF position error at the burst start"}),
            "along_err": (dims, along, {"units": "m", "long_name": "signed along-track EKF error x_est - x_true"}),
            "nis": (dims, nis, {"units": "1", "long_name": "NIS per measurement dimension (NaN: no update)"}),
            "nees": (
                dims,
                nees,
                {"units": "1", "long_name": "position NEES per dimension (estimate against truth, P_pos)"},
            ),
            "snap_err": (
                ("receiver", "measurements", "epoch"),
                snap,
                {"units": "m", "long_name": "2-D snapshot least-squares position error"},
            ),
            "aod_err": (
                ("receiver", "epoch", "slot"),
                meas_aod,
                {"units": "rad", "long_name": "AOD error of the measured RRHs (NaN: not detected)"},
            ),
            "range_err": (
                ("receiver", "epoch", "slot"),
                meas_rng,
                {"units": "m", "long_name": "TOA range error of the measured RRHs (NaN: not detected)"},
            ),
            "t": (("epoch",), ds["t"].values, {"units": "s", "long_name": "time"}),
            "x_true": (("epoch",), ds["x_true"].values, {"units": "m", "long_name": "true position"}),
            "a_true": (("epoch",), ds["a_true"].values, {"units": "m s-2", "long_name": "true acceleration"}),
            "sir_best": (("epoch",), ds["sir_best"].values, dict(ds["sir_best"].attrs)),
        },
        coords={
            "receiver": ("receiver", receivers, {"units": "1", "long_name": "receiver"}),
            "measurements": (
                "measurements",
                measurement_sets,
                {"units": "1", "long_name": "measurements used by the tracker"},
            ),
            "gate": ("gate", [0, 1], {"units": "1", "long_name": "chi2 innovation gate off/on"}),
            "epoch": ("epoch", ds["epoch"].values, {"units": "1", "long_name": "epoch index"}),
            "slot": ("slot", [0, 1, 2], {"units": "1", "long_name": "measured RRH rank by strength"}),
        },
    )


def track_imm(
    ds: xr.Dataset,
    scn: Scenario,
    cal: dict[str, dict],
    imm_params: dict[str, Any],
    tracker: dict[str, Any],
    selection: dict[str, str],
    log,
) -> tuple[xr.Dataset, dict]:
    """The gated AOD+TOA EKF, the IMM (``nr.imm``) and the RTS-smoothed EKF of one receiver
    on one realization (docs/model/nr.md §6), scored against the truth.

    Returns the scores (2-D and along-track errors, position NEES, IMM mode probabilities,
    re-acquisitions, the acceleration changes) and the calibration record the trackers used.
    Raises ``ValueError`` when ``imm_params['receiver']`` was not simulated.

    Parameters
    ----------
    ds : xarray.Dataset
        One realization's estimates (all receivers).
    scn : Scenario
        The scenario (deployment, trajectory).
    cal : dict of str to dict
        Calibration records by :func:`tracker_name`; uses ``<receiver>/aod_toa/gate``.
    imm_params : dict
        The ``nr.imm`` config section: ``receiver``, ``q_quiet`` (m² s⁻⁵; ``None``: the
        calibrated q), ``delta_a_m_s2`` (the acceleration jump the manoeuvre mode covers, m/s²),
        ``sojourn_s`` (mean sojourn per mode, s).
    tracker : dict
        The ``nr.tracker`` config section (uses ``gate_prob``).
    selection : dict of str to str
        Receiver name -> strength measure of its measured RRHs.
    log : logging.Logger
        Receives the settings used.

    Returns
    -------
    tuple of (xarray.Dataset, dict)
        The scores (``pos_err`` and ``along_err`` [m], ``pos_nees`` [1] per (``filter``,
        ``epoch``), filters ``ekf``, ``imm``, ``rts``; ``mode_prob`` [1] per (``mode``, ``epoch``);
        ``q``, ``sojourn_s``, ``n_reacquired``, ``t`` [s], ``x_true`` [m], ``a_true`` [m/s²],
        ``change_epoch`` and ``delta_a`` [m/s²] per ``change``) and the calibration record used.

    Raises
    ------
    ValueError
        When ``imm_params['receiver']`` is not among the simulated receivers.
    """
    dep, traj = scn.deployment, scn.trajectory
    rx = imm_params["receiver"]
    if rx not in [str(r) for r in ds["receiver"].values]:
        raise ValueError(
            f"nr.imm.receiver = {rx!r} is not among the simulated receivers {ds['receiver'].values.tolist()}"
        )
    ds = ds.sel(receiver=rx)
    c = cal[f"{rx}/aod_toa/gate"]
    cfg = TrackerConfig.from_record(c, measurements="aod_toa", gate=True, gate_prob=tracker["gate_prob"])
    q_quiet = c["q"] if imm_params["q_quiet"] is None else float(imm_params["q_quiet"])
    q_man = q_for_jump(imm_params["delta_a_m_s2"], traj.dt_s)
    imm = ImmConfig(q=(q_quiet, q_man), sojourn_s=tuple(imm_params["sojourn_s"]))
    log.info("receiver %s, calibration %s; IMM q = %s m2/s5, sojourn %s s", rx, c, imm.q, imm.sojourn_s)
    out = track_filters(ds, dep.x_m, dep.offset_m, dep.h_bs_m - dep.h_ut_m, traj.dt_s, cfg, imm, strength=selection[rx])
    xs, ps = rts_smooth(out["ekf"]["state"], out["ekf"]["cov"], transition(traj.dt_s), process_noise(traj.dt_s, cfg.q))
    runs = {
        "ekf": (out["ekf"]["state"], out["ekf"]["cov"]),
        "imm": (out["imm"]["state"], out["imm"]["cov"]),
        "rts": (xs, ps),
    }
    return _imm_dataset(ds, traj, imm, out, runs, log), c


def _imm_dataset(ds, traj, imm, out, runs, log) -> xr.Dataset:
    """The IMM run's scores as a Dataset (results/nr/imm/{real}.nc)."""
    x_true = ds["x_true"].values
    n = x_true.size
    pos_err = np.stack([np.hypot(s[:, 0] - x_true, s[:, 1]) for s, _ in runs.values()])
    along = np.stack([s[:, 0] - x_true for s, _ in runs.values()])
    nees = np.stack([position_nees(s, P, x_true) for s, P in runs.values()])
    for i, f in enumerate(runs):
        log.info("%s: mean error %.3f m, mean NEES %.2f", f, np.nanmean(pos_err[i]), np.nanmean(nees[i]))
    ce = change_epochs(traj.phases, traj.dt_s)
    acc = np.array([a for _, a in traj.phases])
    inside = ce < n
    epoch_attrs = {"units": "1", "long_name": "epoch index"}
    n_reacq = [out["ekf"]["reacquired"].sum(), out["imm"]["reacquired"].sum(), out["ekf"]["reacquired"].sum()]
    return xr.Dataset(
        {
            "pos_err": (
                ("filter", "epoch"),
                pos_err,
                {"units": "m", "long_name": "2-D position error at the burst start"},
            ),
            "along_err": (("filter", "epoch"), along, {"units": "m", "long_name": "along-track error x_hat - x_true"}),
            "pos_nees": (
                ("filter", "epoch"),
                nees,
                {"units": "1", "long_name": "2-D position NEES (chi2 with 2 dof if consistent)"},
            ),
            "mode_prob": (("mode", "epoch"), out["imm"]["mu"].T, {"units": "1", "long_name": "IMM mode probability"}),
            "q": (
                ("mode",),
                np.array(imm.q, float),
                {"units": "m2 s-5", "long_name": "white-jerk intensity of the IMM model"},
            ),
            "sojourn_s": (
                ("mode",),
                np.array(imm.sojourn_s, float),
                {"units": "s", "long_name": "mean sojourn time of the IMM mode"},
            ),
            "n_reacquired": (
                ("filter",),
                np.array(n_reacq),
                {"units": "1", "long_name": "re-acquisitions after track loss (RTS: those of its EKF)"},
            ),
            "t": (("epoch",), ds["t"].values, {"units": "s", "long_name": "time"}),
            "x_true": (("epoch",), x_true, {"units": "m", "long_name": "true position"}),
            "a_true": (("epoch",), ds["a_true"].values, {"units": "m s-2", "long_name": "true acceleration"}),
            "change_epoch": (
                ("change",),
                ce[inside],
                {"units": "1", "long_name": "first epoch of a new acceleration phase"},
            ),
            "delta_a": (
                ("change",),
                np.diff(acc)[inside],
                {"units": "m s-2", "long_name": "acceleration jump at the change"},
            ),
        },
        coords={
            "filter": ("filter", list(runs), {"units": "1", "long_name": "tracker"}),
            "mode": ("mode", ["quiet", "manoeuvre"], {"units": "1", "long_name": "IMM model"}),
            "epoch": ("epoch", ds["epoch"].values, epoch_attrs),
            "change": (
                "change",
                np.arange(int(inside.sum())),
                {"units": "1", "long_name": "acceleration change index"},
            ),
        },
    )
