"""Key numbers of the nr study (docs/model/nr.md §10): pooled over realizations, with their spread."""

from __future__ import annotations

import re
from typing import Any

import numpy as np
import xarray as xr

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.keynumbers import KeySpec
from railradio.nr.tracking import loss
from railradio.nr.waveform.numerology import SAMPLE_RATE_HZ

SKIP_S = 5.0  # errors are counted after the first 5 s (docs/model/nr.md §10)

SPECS = {
    "meas.aod_err_deg.p95": ("deg", "95th percentile of |AOD error| of the measured RRHs", 1.3, "<"),
    "meas.toa_err_m.p95": ("m", "95th percentile of |TOA range error| of the measured RRHs", 1.6, "<"),
    "meas.detection_rate": ("1", "share of (epoch, measured RRH) pairs with a valid TOA", None, None),
    "meas.toa_err_m.frac_lt_5m": (
        "1",
        "share of (epoch, measured RRH) pairs with a TOA range error below 5 m",
        None,
        None,
    ),
    "track.aod_toa.err_m.mean": ("m", "mean 2-D position error, EKF with AOD+TOA", 0.66, "="),
    "track.aod_toa.err_m.p95": ("m", "95th percentile of the position error, EKF AOD+TOA", 1.7, "<"),
    "track.aod_toa.err_m.p99": ("m", "99th percentile of the position error, EKF AOD+TOA", 2.3, "<"),
    "track.aod_toa.frac_submeter": ("1", "share of epochs with error < 1 m, EKF AOD+TOA", 0.75, "≈"),
    "track.toa.err_m.mean": ("m", "mean 2-D position error, EKF with TOA", None, None),
    "track.aod.err_m.mean": ("m", "mean 2-D position error, EKF with AOD", None, None),
    "track.aod_toa.err_m.median": ("m", "median 2-D position error, EKF AOD+TOA", None, None),
    "track.aod_toa_gated.err_m.mean": ("m", "mean 2-D position error, EKF AOD+TOA with the chi2 gate", None, None),
    "track.aod_toa_gated.err_m.p95": ("m", "95th percentile of the position error, EKF AOD+TOA, gated", None, None),
    "track.aod_toa_gated.err_m.p99": ("m", "99th percentile of the position error, EKF AOD+TOA, gated", None, None),
    "track.aod_toa_gated.frac_submeter": ("1", "share of epochs with error < 1 m, EKF AOD+TOA, gated", None, None),
    "snapshot.aod_toa.err_m.median": ("m", "median 2-D error of the snapshot LS fix (no tracking)", None, None),
}


def _per_real(tracks: list[xr.Dataset], rx: str, fn) -> tuple[float, float | None]:
    """Pooled value over all realizations and the standard error from their spread."""
    pooled = fn(tracks)
    if len(tracks) < 2:
        return pooled, None
    each = np.array([fn([t]) for t in tracks], dtype=float)
    if not np.all(np.isfinite(each)):  # a realization without a value (e.g. every epoch lost)
        return pooled, None
    return pooled, float(np.std(each, ddof=1) / np.sqrt(len(tracks)))


_ACCURACY = re.compile(r"^track\.(?P<measurements>aod_toa|aod|toa)(?P<gated>_gated)?\.(err|along|cross)_m\.\w+$")
"""An all-epoch accuracy key of a tracker (reported only where the track is rarely lost)."""

TRACK_LOSS_SPECS = {
    "lost_frac": ("1", "share of the scored epochs lost (2-D error above half the RRH spacing)"),
    "time_to_loss_s": (
        "s",
        "time from the run's start to its first lost epoch (mean over the realizations that "
        "lose the track; null if none does)",
    ),
    "tracked.err_m.mean": ("m", "mean 2-D position error over the epochs not lost"),
    "tracked.err_m.p95": ("m", "95th percentile of the 2-D position error over the epochs not lost"),
    "tracked.err_m.p99": ("m", "99th percentile of the 2-D position error over the epochs not lost"),
}
"""Per tracker (receiver × measurement set × gate): ``track.<measurements>[_gated].<metric>``."""

CONSISTENCY_SPECS = {
    "nis.mean": (
        "1",
        "mean NIS per measurement dimension over the epochs with an update (1 for a consistent filter)",
        "nis",
        False,
    ),
    "nees.mean": (
        "1",
        "mean position NEES per dimension over the epochs not lost (1 for a consistent filter)",
        "nees",
        True,
    ),
}
"""Filter consistency per tracker (unit, description, track variable, over tracked epochs
only), where the track datasets carry it."""


def _runs(ts: list[xr.Dataset], rx: str, measurements: str, gate: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """(t, 2-D error) of each realization after the first SKIP_S seconds."""
    out = []
    for t in ts:
        keep = t["t"].values >= SKIP_S
        out.append(
            (t["t"].values[keep], t["pos_err"].sel(receiver=rx, measurements=measurements, gate=gate).values[keep])
        )
    return out


def _loss_fns(spacing_m: float, rx: str, measurements: str, gate: int) -> dict:
    """Each metric of :data:`TRACK_LOSS_SPECS` as a function of a list of track datasets."""

    def tracked(ts):
        err = np.concatenate([e for _, e in _runs(ts, rx, measurements, gate)])
        return err[~loss.lost_mask(err, spacing_m)]

    def stat(v, fn):
        return float(fn(v)) if v.size else np.nan

    return {
        "lost_frac": lambda ts: float(
            np.mean(loss.lost_mask(np.concatenate([e for _, e in _runs(ts, rx, measurements, gate)]), spacing_m))
        ),
        "time_to_loss_s": lambda ts: (lambda v: np.nan if v is None else v)(
            loss.time_to_loss_s(_runs(ts, rx, measurements, gate), spacing_m)
        ),
        "tracked.err_m.mean": lambda ts: stat(tracked(ts), np.mean),
        "tracked.err_m.p95": lambda ts: stat(tracked(ts), lambda v: np.percentile(v, 95)),
        "tracked.err_m.p99": lambda ts: stat(tracked(ts), lambda v: np.percentile(v, 99)),
    }


def _consistency_fn(spacing_m: float, rx: str, measurements: str, gate: int, var: str, tracked_only: bool):
    """Mean of a consistency variable after SKIP_S (over the epochs not lost if asked)."""

    def fn(ts):
        vals = []
        for t in ts:
            keep = t["t"].values >= SKIP_S
            v = t[var].sel(receiver=rx, measurements=measurements, gate=gate).values[keep]
            if tracked_only:
                err = t["pos_err"].sel(receiver=rx, measurements=measurements, gate=gate).values[keep]
                v = v[~loss.lost_mask(err, spacing_m)]
            vals.append(v[np.isfinite(v)])
        v = np.concatenate(vals)
        return float(np.mean(v)) if v.size else np.nan

    return fn


def _spacing(tracks: list[xr.Dataset]) -> float:
    spacings = {loss.rrh_spacing_m(t) for t in tracks}
    if len(spacings) != 1:
        raise ValueError(f"the tracks come from different RRH spacings: {sorted(spacings)}")
    return spacings.pop()


def _metric_fns(rx: str) -> dict:
    """Each key of :data:`SPECS` as a function of a list of track datasets (receiver ``rx``)."""

    def err(ts, measurements, gate=0):
        return np.concatenate(
            [
                t["pos_err"].sel(receiver=rx, measurements=measurements, gate=gate).values[t["t"].values >= SKIP_S]
                for t in ts
            ]
        )

    def along(ts, measurements, gate=0):
        return np.concatenate(
            [
                t["along_err"].sel(receiver=rx, measurements=measurements, gate=gate).values[t["t"].values >= SKIP_S]
                for t in ts
            ]
        )

    def cross(ts, measurements, gate=0):
        e, a = err(ts, measurements, gate), along(ts, measurements, gate)
        return np.sqrt(np.maximum(e**2 - a**2, 0.0))

    def meas(ts, name):
        return np.concatenate([t[name].sel(receiver=rx).values.ravel() for t in ts])

    return {
        "meas.aod_err_deg.p95": lambda ts: float(np.nanpercentile(np.abs(np.degrees(meas(ts, "aod_err"))), 95)),
        "meas.toa_err_m.p95": lambda ts: float(np.nanpercentile(np.abs(meas(ts, "range_err")), 95)),
        "meas.detection_rate": lambda ts: float(np.mean(np.isfinite(meas(ts, "range_err")))),
        "meas.toa_err_m.frac_lt_5m": lambda ts: float(np.mean(np.abs(meas(ts, "range_err")) < 5.0)),
        "meas.toa_err_m.median_abs": lambda ts: float(np.nanmedian(np.abs(meas(ts, "range_err")))),
        "track.aod_toa.err_m.mean": lambda ts: float(np.nanmean(err(ts, "aod_toa"))),
        "track.aod_toa.err_m.p95": lambda ts: float(np.nanpercentile(err(ts, "aod_toa"), 95)),
        "track.aod_toa.err_m.p99": lambda ts: float(np.nanpercentile(err(ts, "aod_toa"), 99)),
        "track.aod_toa.frac_submeter": lambda ts: float(np.mean(err(ts, "aod_toa") < 1.0)),
        "track.toa.err_m.mean": lambda ts: float(np.nanmean(err(ts, "toa"))),
        "track.aod.err_m.mean": lambda ts: float(np.nanmean(err(ts, "aod"))),
        "track.aod_toa.err_m.median": lambda ts: float(np.nanmedian(err(ts, "aod_toa"))),
        "track.aod_toa_gated.err_m.mean": lambda ts: float(np.nanmean(err(ts, "aod_toa", 1))),
        "track.aod_toa_gated.err_m.p95": lambda ts: float(np.nanpercentile(err(ts, "aod_toa", 1), 95)),
        "track.aod_toa_gated.err_m.p99": lambda ts: float(np.nanpercentile(err(ts, "aod_toa", 1), 99)),
        "track.aod_toa_gated.frac_submeter": lambda ts: float(np.mean(err(ts, "aod_toa", 1) < 1.0)),
        "track.aod_toa_gated.along_m.mean": lambda ts: float(np.nanmean(np.abs(along(ts, "aod_toa", 1)))),
        "track.aod_toa_gated.cross_m.mean": lambda ts: float(np.nanmean(cross(ts, "aod_toa", 1))),
        "snapshot.aod_toa.err_m.median": lambda ts: float(
            np.nanmedian(np.concatenate([t["snap_err"].sel(receiver=rx, measurements="aod_toa").values for t in ts]))
        ),
    }


BOUND_SPECS = {
    "nr.bound.toa_crb_m.median": (
        "toa_crb",
        np.median,
        "median TOA range CRB of the best RRH: its detected blocks' "
        "PSS+SSS energy against noise and the other RRHs' SS blocks (interference-limited)",
    ),
    "nr.predict.peb_m.median": (
        "peb",
        np.median,
        "median snapshot position error predicted from the TOA CRB with the "
        "integer-sample floor and the calibration run's AOD spread (a prediction: measured errors)",
    ),
    "nr.predict.pcrb_m.mean": (
        "pcrb",
        np.mean,
        "mean PCRB recursion of the tracked position with the calibrated q and the "
        "measured error levels (white-jerk model; a prediction, not a bound)",
    ),
    "nr.predict.pcrb_true_motion_m.mean": (
        "pcrb_true_motion",
        np.mean,
        "mean PCRB recursion for the true piecewise-constant-acceleration motion (genie knows "
        "the change instants) with the measured error levels (a prediction, not a bound)",
    ),
}


def key_numbers(tracks: list[xr.Dataset], bounds: list[xr.Dataset] | None = None) -> dict[str, Any]:
    """Key numbers of the nr tracks pooled over the realizations (docs/model/nr.md §10), each with
    the standard error of its per-realization values: the PCRB/PEB predictions (``nr.bound.*``,
    with ``bounds``), the median SIR of the strongest RRH, the loss thresholds, and per receiver
    (prefix ``nr.`` for the source's receiver, ``nr.<receiver>.`` for an extra receiver) the track-loss, consistency,
    measurement and accuracy metrics of every tracker (an all-epoch accuracy is null where the
    track is lost too often, :func:`railradio.nr.tracking.loss.accuracy`); errors are counted after
    :data:`SKIP_S`.

    Parameters
    ----------
    tracks : list of xarray.Dataset
        The realizations' track datasets (:func:`railradio.nr.study.runs.track_receivers`).
    bounds : list of xarray.Dataset or None
        The realizations' bound datasets (``t`` [s] and the bound variables [m] per epoch;
        the ``nr_bounds`` rule's output), or ``None``: no ``nr.bound.*`` keys.

    Returns
    -------
    dict of str to dict
        Key name -> its JSON entry (:meth:`railradio.keynumbers.KeySpec.entry`: ``value``,
        ``unit``, ``description``, source value and relation, ``mc_stderr``, optional ``lost_frac``).
    """
    out: dict[str, Any] = {}
    for name, (var, fn, desc) in BOUND_SPECS.items() if bounds else ():
        vals = [float(fn(b[var].values[b["t"].values >= SKIP_S])) for b in bounds]
        pooled = float(fn(np.concatenate([b[var].values[b["t"].values >= SKIP_S] for b in bounds])))
        se = float(np.std(vals, ddof=1) / np.sqrt(len(vals))) if len(vals) > 1 else None
        out[name] = KeySpec(name, "m", desc).entry(pooled, se)
    sir = np.concatenate([t["sir_best"].values for t in tracks])
    out["nr.link.sir_best_db.median"] = KeySpec(
        "nr.link.sir_best_db.median", "dB", "median power of the strongest RRH over the sum of all others in range"
    ).entry(float(np.median(sir)))
    spacing = _spacing(tracks)
    for name, unit, desc, value in (
        ("nr.track.score_from_s", "s", "tracking errors are scored from this time of the run on", SKIP_S),
        (
            "nr.track.lost_threshold_m",
            "m",
            "an epoch is lost when its 2-D error exceeds this (half the RRH spacing)",
            spacing / 2,
        ),
        (
            "nr.track.lost_frac_max",
            "1",
            "an all-epoch accuracy is reported only below this lost share",
            loss.LOST_FRAC_MAX,
        ),
    ):
        out[name] = KeySpec(name, unit, desc).entry(value)
    measurement_sets = [str(v) for v in tracks[0]["measurements"].values]
    for rx in [str(r) for r in tracks[0]["receiver"].values]:
        prefix = "nr." if rx == "source" else f"nr.{rx}."
        who = "" if rx == "source" else f" ({rx} receiver)"
        fns = _metric_fns(rx)
        lost = {}
        for measurements in measurement_sets:
            for gate in (0, 1):
                track = f"track.{measurements}{'_gated' if gate else ''}"
                lfns = _loss_fns(spacing, rx, measurements, gate)
                for metric, (unit, desc) in TRACK_LOSS_SPECS.items():
                    name = f"{prefix}{track}.{metric}"
                    value, se = _per_real(tracks, rx, lfns[metric])
                    out[name] = KeySpec(
                        name, unit, f"{desc}, EKF {measurements}{', gated' if gate else ''}{who}"
                    ).entry(value if np.isfinite(value) else None, se if metric != "time_to_loss_s" else None)
                lost[(measurements, gate)] = out[f"{prefix}{track}.lost_frac"]["value"]
                for metric, (unit, desc, var, tracked_only) in CONSISTENCY_SPECS.items():
                    if var not in tracks[0]:
                        continue
                    name = f"{prefix}{track}.{metric}"
                    fn = _consistency_fn(spacing, rx, measurements, gate, var, tracked_only)
                    value, se = _per_real(tracks, rx, fn)
                    out[name] = KeySpec(
                        name, unit, f"{desc}, EKF {measurements}{', gated' if gate else ''}{who}"
                    ).entry(value if np.isfinite(value) else None, se)
        for key, (unit, desc, src, rel) in SPECS.items():
            name = prefix + key
            if rx != "source":
                src, rel, desc = None, None, f"{desc}{who}"
            value, se = _per_real(tracks, rx, fns[key])
            m = _ACCURACY.match(key)
            if m:  # an all-epoch accuracy: null where the track is lost too often
                lf = lost[(m["measurements"], int(bool(m["gated"])))]
                value = loss.accuracy(value, lf)
                out[name] = KeySpec(name, unit, desc, src, rel).entry(
                    value, se if value is not None else None, lost_frac=lf
                )
                continue
            out[name] = KeySpec(name, unit, desc, src, rel).entry(value if np.isfinite(value) else None, se)
    return out


CALIBRATION_SPECS = {
    "q": ("m2 s-5", "white-jerk intensity q calibrated on the calibration run (position NEES consistency)"),
    "q_at_edge": (
        "1",
        "1 if the calibrated q sits on an edge of the searched range (grid widened by decades up to "
        "1e-6 ... 1e6), else 0",
    ),
    "q_cost_monotone": (
        "1",
        "1 if the search reached the limit of its range with the consistency cost falling "
        "at every decade from the grid's edge on (no q is identified), else 0",
    ),
    "q_cost": ("1", "|log(median NEES / median chi2_2)| of the calibration run at the calibrated q (0: consistent)"),
    "sigma_aod_deg": ("deg", "calibrated AOD standard deviation (inliers of the calibration run's errors)"),
    "sigma_range_m": ("m", "calibrated TOA range standard deviation (inliers of the calibration run's errors)"),
}
"""Per tracker ``cal.<measurements>[_gated].<metric>``, from ``calibration.json``."""


def calibration_key_numbers(cal: dict[str, dict]) -> dict[str, Any]:
    """The calibrated W and q of every tracker (``receiver/measurements/gate|nogate`` records of
    ``calibration.json``) as key numbers.

    Parameters
    ----------
    cal : dict of str to dict
        ``calibration.json``: tracker name (``receiver/measurements/gate|nogate``) -> record
        (``q`` [m² s⁻⁵], ``sigma_aod_rad`` [rad], ``sigma_toa_s`` [s], optional ``q_search``).

    Returns
    -------
    dict of str to dict
        Key name -> its JSON entry (:meth:`railradio.keynumbers.KeySpec.entry`: ``value``,
        ``unit``, ``description``, source value and relation, ``mc_stderr``, optional ``lost_frac``).
        Per tracker ``q``, ``q_at_edge``, ``q_cost_monotone``, ``q_cost``, ``sigma_aod_deg`` [deg],
        ``sigma_range_m`` [m], and with the AOD model per angle bin b ``aod_bias_deg.b<b>`` and
        ``aod_sigma_deg.b<b>`` [deg]; and the counts ``nr.cal.n_trackers``, ``nr.cal.n_q_at_edge``,
        ``nr.cal.n_q_at_edge_monotone``.
    """
    out: dict[str, Any] = {}
    for name, rec in cal.items():
        rx, measurements, gate = name.split("/")
        prefix = "nr." if rx == "source" else f"nr.{rx}."
        track = f"cal.{measurements}{'_gated' if gate == 'gate' else ''}"
        search = rec.get("q_search", {})
        i = search["q"].index(rec["q"]) if rec["q"] in search.get("q", []) else None
        values = {
            "q": rec["q"],
            "q_at_edge": float(search["at_edge"]) if search else None,
            "q_cost_monotone": float(search["monotone"]) if search else None,
            "q_cost": search["cost"][i] if i is not None else None,
            "sigma_aod_deg": float(np.degrees(rec["sigma_aod_rad"])),
            "sigma_range_m": rec["sigma_toa_s"] * SPEED_OF_LIGHT_M_S,
        }
        who = "" if rx == "source" else f" ({rx} receiver)"
        what = f"EKF {measurements}{', gated' if gate == 'gate' else ''}{who}"
        for metric, (unit, desc) in CALIBRATION_SPECS.items():
            key = f"{prefix}{track}.{metric}"
            out[key] = KeySpec(key, unit, f"{desc}, {what}").entry(values[metric])
        edges_deg = np.degrees(rec.get("aod_angle_edges_rad", []))
        bins = zip(rec.get("aod_bias_bins_rad", []), rec.get("sigma_aod_angle_bins_rad", []), strict=True)
        for b, (bias, sig) in enumerate(bins):
            lo = f"{edges_deg[b - 1]:g}" if b else "0"
            hi = f"{edges_deg[b]:g}" if b < edges_deg.size else "90"
            where = f"at {lo}-{hi} deg from endfire (true angle)"
            for metric, v, desc in (
                ("aod_bias_deg", bias, "calibrated AOD bias toward broadside"),
                ("aod_sigma_deg", sig, "calibrated AOD standard deviation about that bias"),
            ):
                key = f"{prefix}{track}.{metric}.b{b}"
                out[key] = KeySpec(key, "deg", f"{desc} {where}, {what}").entry(float(np.degrees(v)))
    edges = [k for k in out if k.endswith(".q_at_edge") and out[k]["value"] == 1.0]
    for key, desc, value in (
        ("nr.cal.n_trackers", "trackers calibrated (receiver x measurement set x gate)", len(cal)),
        ("nr.cal.n_q_at_edge", "calibrated q on an edge of the searched range", len(edges)),
        (
            "nr.cal.n_q_at_edge_monotone",
            "of those, with a cost monotone in q (no q identified)",
            sum(out[k[: -len("q_at_edge")] + "q_cost_monotone"]["value"] == 1.0 for k in edges),
        ),
    ):
        out[key] = KeySpec(key, "1", desc).entry(float(value))
    return out


SENSITIVITY_SPECS = {
    "meas.toa_err_m.median_abs": ("m", "median |TOA range error| of the measured RRHs (valid TOAs)"),
    "track.aod_toa_gated.along_m.mean": ("m", "mean |along-track error| of the gated EKF AOD+TOA"),
    "track.aod_toa_gated.cross_m.mean": ("m", "mean |cross-track error| of the gated EKF AOD+TOA"),
}
"""Metrics of the sensitivity cases only (unit, description), beside :data:`SPECS`."""

SENSITIVITY_METRICS = (
    "meas.detection_rate",
    "meas.toa_err_m.frac_lt_5m",
    "meas.toa_err_m.median_abs",
    "meas.toa_err_m.p95",
    "meas.aod_err_deg.p95",
    "track.aod_toa.err_m.mean",
    "track.aod_toa_gated.err_m.mean",
    "track.aod_toa_gated.err_m.p95",
    "track.aod_toa_gated.along_m.mean",
    "track.aod_toa_gated.cross_m.mean",
)


SENSITIVITY_LOSS_METRICS = ("lost_frac", "time_to_loss_s", "tracked.err_m.mean", "tracked.err_m.p95")
"""Loss metrics of the sensitivity cases' AOD+TOA trackers (gate off and on)."""


def sensitivity_key_numbers(
    base: xr.Dataset, cases: dict[str, xr.Dataset], n_epochs: int | dict[str, int]
) -> dict[str, Any]:
    """Key numbers ``sens.nr.<case>.<receiver>.<metric>`` of the sensitivity cases and of
    ``base`` (the main run's realization r0, with the main calibration), all on the first
    ``n_epochs`` epochs (a tracker-only case tracks the main run's whole r0), or per case
    (a dict case -> epochs, ``"base"`` included: the cheap sweep points run fewer): one
    realization each, paired (same bursts' random draws), so no Monte Carlo error is
    attached.

    Parameters
    ----------
    base : xarray.Dataset
        Track dataset of the main run's r0 (:func:`railradio.nr.study.runs.track_receivers`).
    cases : dict of str to xarray.Dataset
        Case name -> its track dataset of r0.
    n_epochs : int or dict of str to int
        Epochs scored (the first ones), for all runs or per case (``"base"`` included).

    Returns
    -------
    dict of str to dict
        Key name -> its JSON entry (:meth:`railradio.keynumbers.KeySpec.entry`: ``value``,
        ``unit``, ``description``, source value and relation, ``mc_stderr``, optional ``lost_frac``).

    Raises
    ------
    ValueError
        When a run has fewer epochs than it is to be scored on.
    """
    out: dict[str, Any] = {}
    runs = {"base": base} | dict(cases)
    for case, ds in runs.items():
        n = n_epochs[case] if isinstance(n_epochs, dict) else n_epochs
        if ds.sizes["epoch"] < n:
            raise ValueError(f"case {case!r} has {ds.sizes['epoch']} epochs, fewer than n_epochs={n}")
        ds = ds.isel(epoch=slice(0, n))  # a causal tracker: the same as a shorter run
        spacing = _spacing([ds])
        for rx in [str(r) for r in ds["receiver"].values]:
            fns = _metric_fns(rx)
            where = f"({rx} receiver, sensitivity case {case}, first {n} epochs of r0)"
            lost = {}
            for gate in (0, 1):
                track = f"track.aod_toa{'_gated' if gate else ''}"
                lfns = _loss_fns(spacing, rx, "aod_toa", gate)
                for metric in SENSITIVITY_LOSS_METRICS:
                    unit, desc = TRACK_LOSS_SPECS[metric]
                    name = f"sens.nr.{case}.{rx}.{track}.{metric}"
                    value = lfns[metric]([ds])
                    out[name] = KeySpec(name, unit, f"{desc}, EKF AOD+TOA{', gated' if gate else ''} {where}").entry(
                        value if np.isfinite(value) else None
                    )
                lost[gate] = out[f"sens.nr.{case}.{rx}.{track}.lost_frac"]["value"]
            for metric in SENSITIVITY_METRICS:
                unit, desc = (SPECS | SENSITIVITY_SPECS)[metric][:2]
                name = f"sens.nr.{case}.{rx}.{metric}"
                value = fns[metric]([ds])
                m = _ACCURACY.match(metric)
                if m:
                    lf = lost[int(bool(m["gated"]))]
                    out[name] = KeySpec(name, unit, f"{desc} {where}").entry(loss.accuracy(value, lf), lost_frac=lf)
                    continue
                out[name] = KeySpec(name, unit, f"{desc} {where}").entry(value if np.isfinite(value) else None)
    return out


def toa_floor_m(sync_sigma_s: float = 0.0, q: float = 0.5) -> float:
    """``q``-quantile of |e| for e = u + c·δ: the integer-sample TOA error u ~ U(±c/(2F_s))
    plus a Gaussian clock offset δ ~ N(0, σ²) [m] — the floor of the source's TOA estimator
    when the RRH clocks are off by σ (exact: CDF by quadrature, quantile by root finding).

    Parameters
    ----------
    sync_sigma_s : float
        Standard deviation σ of the RRH clock offsets, s (≥ 0).
    q : float
        Quantile, in (0, 1).

    Returns
    -------
    float
        The ``q``-quantile of |e|, m.

    Raises
    ------
    ValueError
        When ``sync_sigma_s`` < 0 (or is NaN).
    """
    from scipy.integrate import quad
    from scipy.optimize import brentq
    from scipy.stats import norm

    if not sync_sigma_s >= 0:
        raise ValueError(f"sync_sigma_s must be >= 0, got {sync_sigma_s!r}")
    half = SPEED_OF_LIGHT_M_S / SAMPLE_RATE_HZ / 2
    s = SPEED_OF_LIGHT_M_S * sync_sigma_s
    if s == 0:
        return q * half

    def cdf(x):
        return quad(lambda u: norm.cdf((x - u) / s) - norm.cdf((-x - u) / s), -half, half)[0] / (2 * half)

    return float(brentq(lambda x: cdf(x) - q, 0.0, half + 10 * s))


def sensitivity_floor_numbers(sync_sigma_s: dict[str, float]) -> dict[str, Any]:
    """Key numbers ``sens.nr.<case>.bound.toa_floor_m.median``: the median |TOA error| floor
    (:func:`toa_floor_m`) of each case with its RRH clock spread σ [s], beside the cases'
    ``meas.toa_err_m.median_abs``.

    Parameters
    ----------
    sync_sigma_s : dict of str to float
        Case name -> RRH clock spread σ, s (:func:`railradio.nr.study.cases.sync_sigma_s`).

    Returns
    -------
    dict of str to dict
        Key name -> its JSON entry (:meth:`railradio.keynumbers.KeySpec.entry`: ``value``,
        ``unit``, ``description``, source value and relation, ``mc_stderr``, optional ``lost_frac``).
    """
    out: dict[str, Any] = {}
    for case, sigma in sync_sigma_s.items():
        name = f"sens.nr.{case}.bound.toa_floor_m.median"
        out[name] = KeySpec(
            name,
            "m",
            "median of |integer-sample TOA error + c x RRH clock offset| "
            f"(uniform +-c/(2F_s) and N(0, sigma^2), sigma = {sigma:g} s; case {case})",
        ).entry(toa_floor_m(float(sigma)))
    return out
