"""Key numbers of the nr study (STUDY.md §2.6): pooled over realizations, with their spread."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from railradio.keynumbers import KeySpec

SKIP_S = 5.0  # errors are counted after the first 5 s (STUDY.md §2.6)

SPECS = {
    "meas.aod_err_deg.p95": ("deg", "95th percentile of |AOD error| of the measured RRHs", 1.3, "<"),
    "meas.toa_err_m.p95": ("m", "95th percentile of |TOA range error| of the measured RRHs", 1.6, "<"),
    "meas.detection_rate": ("1", "share of (epoch, measured RRH) pairs with a valid TOA", None, None),
    "meas.toa_err_m.frac_lt_5m": ("1", "share of (epoch, measured RRH) pairs with a TOA range error below 5 m", None, None),
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
    each = np.array([fn([t]) for t in tracks])
    return pooled, float(np.std(each, ddof=1) / np.sqrt(len(tracks)))


def _metric_fns(rx: str) -> dict:
    """Each key of :data:`SPECS` as a function of a list of track datasets (receiver ``rx``)."""

    def err(ts, variant, gate=0):
        return np.concatenate([t["pos_err"].sel(receiver=rx, variant=variant, gate=gate).values[t["t"].values >= SKIP_S]
                               for t in ts])

    def meas(ts, name):
        return np.concatenate([t[name].sel(receiver=rx).values.ravel() for t in ts])

    return {
        "meas.aod_err_deg.p95": lambda ts: float(np.nanpercentile(np.abs(np.degrees(meas(ts, "aod_err"))), 95)),
        "meas.toa_err_m.p95": lambda ts: float(np.nanpercentile(np.abs(meas(ts, "range_err")), 95)),
        "meas.detection_rate": lambda ts: float(np.mean(np.isfinite(meas(ts, "range_err")))),
        "meas.toa_err_m.frac_lt_5m": lambda ts: float(np.mean(np.abs(meas(ts, "range_err")) < 5.0)),
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
        "snapshot.aod_toa.err_m.median": lambda ts: float(np.nanmedian(np.concatenate(
            [t["snap_err"].sel(receiver=rx, variant="aod_toa").values for t in ts]))),
    }


BOUND_SPECS = {
    "nr.bound.toa_crb_m.median": ("toa_crb", np.median, "median TOA range CRB of the best RRH (interference-limited)"),
    "nr.bound.peb_m.median": ("peb", np.median, "median snapshot position bound (integer-sample TOA floor included)"),
    "nr.bound.pcrb_m.mean": ("pcrb", np.mean, "mean posterior CRB of the tracked position (white-jerk model, calibrated q)"),
    "nr.bound.pcrb_true_motion_m.mean": ("pcrb_true_motion", np.mean,
                                         "mean posterior CRB for the true piecewise-constant-acceleration motion (genie knows the change instants)"),
}


def key_numbers(tracks: list[xr.Dataset], bounds: list[xr.Dataset] | None = None) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for name, (var, fn, desc) in (BOUND_SPECS.items() if bounds else ()):
        vals = [float(fn(b[var].values[b["t"].values >= SKIP_S])) for b in bounds]
        pooled = float(fn(np.concatenate([b[var].values[b["t"].values >= SKIP_S] for b in bounds])))
        se = float(np.std(vals, ddof=1) / np.sqrt(len(vals))) if len(vals) > 1 else None
        out[name] = KeySpec(name, "m", desc).entry(pooled, se)
    sir = np.concatenate([t["sir_best"].values for t in tracks])
    out["nr.link.sir_best_db.median"] = KeySpec(
        "nr.link.sir_best_db.median", "dB",
        "median power of the strongest RRH over the sum of all others in range").entry(float(np.median(sir)))
    for rx in [str(r) for r in tracks[0]["receiver"].values]:
        prefix = "nr." if rx == "seed" else f"nr.{rx}."
        fns = _metric_fns(rx)
        for key, (unit, desc, src, rel) in SPECS.items():
            name = prefix + key
            if rx != "seed":
                src, rel, desc = None, None, f"{desc} ({rx} receiver)"
            value, se = _per_real(tracks, rx, fns[key])
            out[name] = KeySpec(name, unit, desc, src, rel).entry(value if np.isfinite(value) else None, se)
    return out


SENSITIVITY_METRICS = (
    "meas.detection_rate",
    "meas.toa_err_m.frac_lt_5m",
    "meas.toa_err_m.p95",
    "meas.aod_err_deg.p95",
    "track.aod_toa.err_m.mean",
    "track.aod_toa_gated.err_m.mean",
    "track.aod_toa_gated.err_m.p95",
)


def sensitivity_key_numbers(base: xr.Dataset, cases: dict[str, xr.Dataset],
                            n_epochs: int) -> dict[str, Any]:
    """Key numbers ``sens.nr.<case>.<receiver>.<metric>`` of the sensitivity cases and of
    ``base`` (the main run's realization r0, with the main calibration), all on the first
    ``n_epochs`` epochs (a tracker-only case tracks the main run's whole r0): one
    realization each, paired (same bursts' random draws), so no Monte Carlo error is
    attached."""
    out: dict[str, Any] = {}
    runs = {"base": base} | dict(cases)
    for case, ds in runs.items():
        if ds.sizes["epoch"] < n_epochs:
            raise ValueError(f"case {case!r} has {ds.sizes['epoch']} epochs, fewer than n_epochs={n_epochs}")
        ds = ds.isel(epoch=slice(0, n_epochs))  # a causal tracker: the same as a shorter run
        for rx in [str(r) for r in ds["receiver"].values]:
            fns = _metric_fns(rx)
            for metric in SENSITIVITY_METRICS:
                unit, desc = SPECS[metric][:2]
                name = f"sens.nr.{case}.{rx}.{metric}"
                value = fns[metric]([ds])
                out[name] = KeySpec(name, unit, f"{desc} ({rx} receiver, sensitivity case {case}, "
                                    f"first {n_epochs} epochs of r0)").entry(value if np.isfinite(value) else None)
    return out
