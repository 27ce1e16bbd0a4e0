"""What a map cell's accuracy depends on: the AOD near endfire and the error's direction
(docs/model/nr.md §6, §10). Scoring only: every function here reads the truth.

- :func:`diagnostic_key_numbers`: the selected RRHs' |AOD error| within and beyond
  :data:`ENDFIRE_DEG` of the track direction, their share there, and the SS blocks detected.
- :func:`endfire_bias_key_numbers`: the AOD error's bias toward broadside per bin of the true
  angle from endfire, measured on the cell's segment (the quantity the tracker's AOD model,
  :mod:`railradio.nr.tracking.aod_model`, calibrates on the cell's calibration run).
- :func:`along_cross_key_numbers`: the AOD+TOA tracker's mean |error| along and across the
  track; :func:`calibration_diag_key_numbers`: the q each tracker was calibrated with.
- :func:`nearest_key_numbers`: the measurements of the RRH nearest the train, whichever the
  receiver selects (the sanity row's one RRH in range); :func:`off_air_key_numbers`: how many
  of the selected measurements are of RRHs not on the air (beyond the range synthesized), how
  many of those share the nearest RRH's PSS, and how many lie at its delay.
"""

from __future__ import annotations

from typing import Any

import numpy as np

import railradio.nr.tracking.aod_model as aod_model
from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.keynumbers import KeySpec
from railradio.nr.channel.antenna import wrap_rad
from railradio.nr.study.block_bootstrap import nanpercentile
from railradio.nr.study.reproduction_map import CLAIMS, status
from railradio.nr.tracking import loss

ENDFIRE_DEG = 3.0
"""Diagnostics: AOD errors of the RRHs seen within this angle of the track direction (the
ULA's endfire, where neighbouring beams have nearly equal gain) apart from the others."""

ENDFIRE_EDGES_DEG = (1.0, 2.0, 5.0, 10.0, 20.0)
"""Diagnostics: bins of the angle from endfire for the AOD bias (the 1–2–5 series, fixed
before the run; whether or not the tracker models the bias, ``nr.tracker.aod_angle_edges_deg``)."""

LOCK_M = 10.0
"""An off-air selection whose TOA lies within this range [m] of the nearest RRH's true delay
is counted as locked onto that RRH (≈ 4 lags of the correlation's 2.44 m search grid)."""

MIN_PER_BIN = 20
"""Fewest AOD errors in an angle bin for its segment bias to be reported (else null)."""


def _finite(v: float) -> float | None:
    return float(v) if np.isfinite(v) else None


def diagnostic_key_numbers(
    cell: str, rx: str, aod_err_rad: np.ndarray, aod_true_rad: np.ndarray, n_detected: np.ndarray, where: str
) -> dict[str, Any]:
    """What the AOD claim depends on, per cell and receiver: the median |AOD error| of the
    selected RRHs within / beyond :data:`ENDFIRE_DEG` of the track direction, their share
    within it, and the median number of SS blocks detected per selected RRH.

    Parameters
    ----------
    cell, rx : str
        The cell and receiver names.
    aod_err_rad : numpy.ndarray
        AOD errors of the selected RRHs, rad (NaN: none).
    aod_true_rad : numpy.ndarray
        Their true AODs (same shape), rad.
    n_detected : numpy.ndarray
        SS blocks detected per selected RRH.
    where : str
        Text appended to each key's description.

    Returns
    -------
    dict of str to dict
        Key name -> its JSON entry (:meth:`railradio.keynumbers.KeySpec.entry`).
        ``nr.map.<cell>.<rx>.diag.*``: ``aod_err_deg.median_endfire`` and
        ``aod_err_deg.median_broadside`` [deg], ``frac_endfire`` (1), ``n_detected.median``.
    """
    deg = np.degrees(np.asarray(aod_true_rad, float)) % 180.0
    off = np.minimum(deg, 180.0 - deg)
    e = np.abs(np.degrees(aod_err_rad))
    ok = np.isfinite(e) & np.isfinite(off)
    near = ok & (off < ENDFIRE_DEG)
    p = f"nr.map.{cell}.{rx}.diag"
    vals = {
        "aod_err_deg.median_endfire": (
            "deg",
            f"median |AOD error| of the selected RRHs within {ENDFIRE_DEG:g} deg of the track direction",
            np.median(e[near]) if near.any() else np.nan,
        ),
        "aod_err_deg.median_broadside": (
            "deg",
            f"median |AOD error| of the selected RRHs beyond {ENDFIRE_DEG:g} deg of the track direction",
            np.median(e[ok & ~near]) if (ok & ~near).any() else np.nan,
        ),
        "frac_endfire": (
            "1",
            f"share of the selected RRHs seen within {ENDFIRE_DEG:g} deg of the track direction",
            near.sum() / ok.sum() if ok.any() else np.nan,
        ),
        "n_detected.median": (
            "1",
            "median number of SS blocks detected per selected RRH",
            np.median(n_detected[ok]) if ok.any() else np.nan,
        ),
    }
    return {f"{p}.{k}": KeySpec(f"{p}.{k}", u, f"{d} ({where})").entry(_finite(v)) for k, (u, d, v) in vals.items()}


def endfire_bias_key_numbers(
    cell: str, rx: str, aod_err_rad: np.ndarray, aod_true_rad: np.ndarray, edges_deg: tuple[float, ...], where: str
) -> dict[str, Any]:
    """The selected RRHs' AOD bias toward broadside per bin of the true angle from endfire,
    measured on the cell's segment (scoring: the true angle picks the bin).

    Parameters
    ----------
    cell, rx : str
        The cell and receiver names.
    aod_err_rad : numpy.ndarray
        AOD errors θ̂ − θ of the selected RRHs, rad (NaN: none).
    aod_true_rad : numpy.ndarray
        Their true azimuths θ (same shape), rad, the tracker's convention.
    edges_deg : tuple of float
        Increasing bin edges of the angle from endfire, deg (:data:`ENDFIRE_EDGES_DEG`).
    where : str
        Text appended to each key's description.

    Returns
    -------
    dict of str to dict
        ``nr.map.<cell>.<rx>.diag.aod_bias_deg.b<i>`` [deg] (bin i of ``len(edges_deg) + 1``;
        null with fewer than :data:`MIN_PER_BIN` errors) and ``diag.aod_n.b<i>`` (errors in it).

    Raises
    ------
    ValueError
        When the edges are not increasing inside (0°, 90°) or the arrays differ in shape.
    """
    e = np.asarray(aod_err_rad, float).ravel()
    th = np.asarray(aod_true_rad, float).ravel()
    if np.asarray(aod_err_rad).shape != np.asarray(aod_true_rad).shape:
        raise ValueError("aod_err_rad and aod_true_rad must share a shape")
    edges = tuple(np.radians(np.asarray(edges_deg, float)))
    bias, _ = aod_model.fit(e, th, edges, lambda x: 1.4826 * float(np.median(np.abs(x))), MIN_PER_BIN)
    ok = np.isfinite(e) & np.isfinite(th)
    counts = np.bincount(aod_model.bin_index(aod_model.endfire_angle(th[ok])[0], edges), minlength=len(edges) + 1)
    lows = (0.0, *edges_deg)
    highs = (*edges_deg, 90.0)
    p = f"nr.map.{cell}.{rx}.diag"
    out: dict[str, Any] = {}
    for i, (b, n, lo, hi) in enumerate(zip(bias, counts, lows, highs, strict=True)):
        span = f"{lo:g}-{hi:g} deg from endfire"
        name = f"{p}.aod_bias_deg.b{i}"
        out[name] = KeySpec(
            name, "deg", f"median AOD error toward broadside of the selected RRHs seen {span}, on the segment ({where})"
        ).entry(float(np.degrees(b)) if n >= MIN_PER_BIN else None)
        name = f"{p}.aod_n.b{i}"
        out[name] = KeySpec(name, "1", f"AOD errors of the selected RRHs seen {span} ({where})").entry(float(n))
    return out


def calibration_diag_key_numbers(cell: str, rx: str, calibration: dict[str, dict], where: str) -> dict[str, Any]:
    """The q each of the cell's trackers was calibrated with on the cell's own calibration run
    (``nr.map.<cell>.<rx>.diag.q.<measurements>`` [m² s⁻⁵]): the map's EKF errors follow it,
    and its NEES cost does not identify it (docs/model/nr.md §6).

    Parameters
    ----------
    cell, rx : str
        The cell and receiver names.
    calibration : dict of str to dict
        The cell's calibration records, ``<rx>/<measurements>`` -> record with ``q``.
    where : str
        Text appended to each key's description.

    Returns
    -------
    dict of str to dict
        Key name -> its JSON entry.
    """
    out: dict[str, Any] = {}
    for name, rec in calibration.items():
        r, measurements = name.split("/")
        if r != rx:
            continue
        key = f"nr.map.{cell}.{rx}.diag.q.{measurements}"
        out[key] = KeySpec(
            key, "m2 s-5", f"q of the EKF {measurements}, calibrated on the cell's calibration run ({where})"
        ).entry(float(rec["q"]))
    return out


def along_cross_key_numbers(
    cell: str, rx: str, along_err_m: np.ndarray, pos_err_m: np.ndarray, spacing_m: float, where: str
) -> dict[str, Any]:
    """The AOD+TOA tracker's mean |error| along and across the track on the cell's segment
    (null when the track is lost: :func:`railradio.nr.tracking.loss.accuracy`).

    Parameters
    ----------
    cell, rx : str
        The cell and receiver names.
    along_err_m : numpy.ndarray
        [n] signed along-track errors x̂ − x, m.
    pos_err_m : numpy.ndarray
        [n] 2-D position errors, m (the cross-track error is √(pos² − along²)).
    spacing_m : float
        RRH spacing, m (an epoch is lost beyond half of it).
    where : str
        Text appended to each key's description.

    Returns
    -------
    dict of str to dict
        ``nr.map.<cell>.<rx>.diag.track.aod_toa.{along,cross}_m.mean`` [m], each with the
        tracker's lost share.

    Raises
    ------
    ValueError
        When the arrays differ in shape.
    """
    a = np.asarray(along_err_m, float)
    e = np.asarray(pos_err_m, float)
    if a.shape != e.shape:
        raise ValueError(f"along_err_m and pos_err_m must share a shape, got {a.shape} and {e.shape}")
    lost = float(np.mean(loss.lost_mask(e, spacing_m))) if e.size else 1.0
    cross = np.sqrt(np.maximum(e**2 - a**2, 0.0))
    p = f"nr.map.{cell}.{rx}.diag.track.aod_toa"
    out: dict[str, Any] = {}
    for side, x in (("along", np.abs(a)), ("cross", cross)):
        name = f"{p}.{side}_m.mean"
        value = loss.accuracy(float(np.nanmean(x)), lost) if np.isfinite(x).any() else None
        out[name] = KeySpec(name, "m", f"mean |{side}-track error| of the EKF AOD+TOA ({where})").entry(
            value, lost_frac=lost
        )
    return out


def _nearest_column(ds, rrh_x_m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The RRH nearest the train along the track per epoch (ties: the lower index), its
    candidate column and whether it is a candidate: ([n], [n, 1], [n])."""
    x = np.asarray(ds["x_true"].values, float)
    nearest = np.argmin(np.abs(np.asarray(rrh_x_m, float)[None, :] - x[:, None]), axis=1)
    hit = ds["rrh"].values == nearest[:, None]
    return nearest, np.argmax(hit, axis=1)[:, None], hit.any(axis=1)


def nearest_errors(ds, rrh_x_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The AOD and TOA range errors of the RRH nearest the train along the track, per epoch
    (NaN where it is not among the candidates or not measured). Scoring: reads the truth.

    Parameters
    ----------
    ds : xarray.Dataset
        One receiver's estimates (dims ``epoch`` × ``cand``: ``rrh``, ``aod_hat`` [rad],
        ``aod_true``, ``toa_hat`` [s], ``toa_true``; ``x_true`` [m] per epoch).
    rrh_x_m : numpy.ndarray
        [n_rrh] along-track positions of the RRHs, m.

    Returns
    -------
    tuple of numpy.ndarray
        ([n] AOD errors [rad, wrapped to (-π, π]], [n] TOA range errors c·Δτ [m]).

    Raises
    ------
    ValueError
        When ``rrh_x_m`` is empty.
    """
    if np.asarray(rrh_x_m).size == 0:
        raise ValueError("rrh_x_m must hold at least one RRH position")
    _, col, has = _nearest_column(ds, rrh_x_m)

    def at(v):
        return np.take_along_axis(ds[v].values, col, axis=1)[:, 0]

    aod = np.where(has, wrap_rad(at("aod_hat") - at("aod_true")), np.nan)
    rng = np.where(has, (at("toa_hat") - at("toa_true")) * SPEED_OF_LIGHT_M_S, np.nan)
    return aod, rng


def nearest_key_numbers(
    cell: str, rx: str, aod_err_rad: np.ndarray, range_err_m: np.ndarray, idx: np.ndarray, confidence: float, where: str
) -> dict[str, Any]:
    """The receiver's measurements of the RRH nearest the train, whatever the selection: the
    95th percentiles of its |AOD error| and |TOA range error| over the epochs it was measured,
    each with its block-bootstrap interval and the status of the source's claim on it (AOD
    p95 < 1.3°, TOA p95 < 1.6 m, by the map's claim rule), and the share of epochs it was
    measured. In the sanity row (:data:`railradio.nr.study.reproduction_map.SINGLE_CELL`) the
    nearest RRH is the one in range: the receiver's accuracy without interference.

    Parameters
    ----------
    cell, rx : str
        The cell and receiver names.
    aod_err_rad, range_err_m : numpy.ndarray
        [n] the nearest RRH's AOD error [rad] and TOA range error [m] per epoch (NaN: not
        measured).
    idx : numpy.ndarray of int
        [n_boot, n] the bootstrap's resampled epochs
        (:func:`railradio.nr.study.block_bootstrap.block_indices`).
    confidence : float
        Confidence of the interval, in (0, 1).
    where : str
        Text appended to each key's description.

    Returns
    -------
    dict of str to dict
        ``nr.map.<cell>.<rx>.diag.nearest.meas.{aod_err_deg,toa_err_m}.p95`` [deg, m] (the
        map's metric names) with ``.lo``/``.hi`` and ``claim.{aod_p95,toa_p95}`` (1 holds, 0 not resolved, -1 fails;
        a percentile null when never measured), and ``measured_frac`` (1).

    Raises
    ------
    ValueError
        When the arrays differ in shape, ``idx`` does not index them or ``confidence`` is
        outside (0, 1).
    """
    if not 0 < confidence < 1:
        raise ValueError(f"confidence must be in (0, 1), got {confidence!r}")
    a = np.abs(np.degrees(np.asarray(aod_err_rad, float)))
    r = np.abs(np.asarray(range_err_m, float))
    if a.shape != r.shape:
        raise ValueError(f"aod_err_rad and range_err_m must share a shape, got {a.shape} and {r.shape}")
    idx = np.asarray(idx)
    if idx.ndim != 2 or idx.shape[1] != a.size:
        raise ValueError(f"idx must be [n_boot, {a.size}] resampled epochs, got shape {idx.shape}")
    ok = np.isfinite(a) & np.isfinite(r)
    a, r = np.where(ok, a, np.nan), np.where(ok, r, np.nan)
    lo_q, hi_q = (1 - confidence) / 2, 1 - (1 - confidence) / 2
    p = f"nr.map.{cell}.{rx}.diag.nearest"
    out: dict[str, Any] = {}
    for metric, claim, desc, x in (
        ("meas.aod_err_deg.p95", "aod_p95", "95th percentile of the nearest RRH's |AOD error|", a),
        ("meas.toa_err_m.p95", "toa_p95", "95th percentile of the nearest RRH's |TOA range error|", r),
    ):
        unit = CLAIMS[claim].unit
        point = float(np.percentile(x[ok], 95)) if ok.any() else None
        boot = nanpercentile(x[idx], 95)
        lo, hi = (
            (float(np.quantile(boot, lo_q)), float(np.quantile(boot, hi_q)))
            if point is not None and np.all(np.isfinite(boot))
            else (None, None)
        )
        name = f"{p}.{metric}"
        out[name] = KeySpec(name, unit, f"{desc}, over the epochs it was measured ({where})").entry(point)
        for end, v in (("lo", lo), ("hi", hi)):
            out[f"{name}.{end}"] = KeySpec(
                f"{name}.{end}",
                unit,
                f"{'lower' if end == 'lo' else 'upper'} end of the {confidence:.0%} block-bootstrap interval of "
                f"the nearest RRH's {metric} ({where})",
            ).entry(v)
        out[f"{p}.claim.{claim}"] = KeySpec(
            f"{p}.claim.{claim}",
            "1",
            f"source claim '{CLAIMS[claim].label}' on the nearest RRH's measurements: 1 holds, 0 not resolved, "
            f"-1 fails ({where})",
        ).entry(status(CLAIMS[claim], lo, hi, False))
    name = f"{p}.measured_frac"
    out[name] = KeySpec(name, "1", f"share of epochs with the nearest RRH measured (AOD and TOA) ({where})").entry(
        float(ok.mean()) if ok.size else None
    )
    return out


def off_air_selections(
    ds, order: np.ndarray, ok: np.ndarray, rrh_x_m: np.ndarray, offset_m: float, range_m: float, n_id2: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which selected measurements are of RRHs not on the air (2-D distance beyond the range
    synthesized, ``nr.radio.range_m``), which of those share their N_ID2 (their PSS) with the
    RRH nearest the train, and which lie at that RRH's delay (within :data:`LOCK_M`). Scoring:
    reads the truth.

    Parameters
    ----------
    ds : xarray.Dataset
        One receiver's estimates (``rrh``, ``toa_hat`` [s], ``toa_true`` [s] per (``epoch``,
        ``cand``); ``x_true`` [m] per epoch).
    order, ok : numpy.ndarray
        [n, n_use] the selected candidate columns and whether each holds a measurement
        (:func:`railradio.nr.tracking.calibration.selected`).
    rrh_x_m : numpy.ndarray
        [n_rrh] along-track positions of the RRHs, m.
    offset_m : float
        The RRHs' lateral offset from the track, m.
    range_m : float
        The range within which RRHs are synthesized, m (2-D distance).
    n_id2 : numpy.ndarray of int
        [n_rrh] each RRH's N_ID2.

    Returns
    -------
    tuple of numpy.ndarray of bool
        (off_air, shares_pss, locked), each [n, n_use]; the last two within the first.

    Raises
    ------
    ValueError
        When ``order`` and ``ok`` differ in shape, ``rrh_x_m`` is empty, ``n_id2`` does not
        give one N_ID2 per RRH, or ``range_m`` is not positive.
    """
    rrh_x = np.asarray(rrh_x_m, float)
    if np.shape(order) != np.shape(ok):
        raise ValueError(f"order and ok must share a shape, got {np.shape(order)} and {np.shape(ok)}")
    if rrh_x.size == 0:
        raise ValueError("rrh_x_m must hold at least one RRH position")
    if np.size(n_id2) != rrh_x.size:
        raise ValueError(f"n_id2 must give one N_ID2 per RRH ({rrh_x.size}), got {np.size(n_id2)}")
    if not range_m > 0:
        raise ValueError(f"range_m must be > 0, got {range_m!r}")
    x = np.asarray(ds["x_true"].values, float)
    cand = np.take_along_axis(ds["rrh"].values, order, axis=1)
    off = ok & (np.hypot(rrh_x[np.maximum(cand, 0)] - x[:, None], offset_m) > range_m)
    nearest, col, has = _nearest_column(ds, rrh_x)
    pss = off & (np.asarray(n_id2)[np.maximum(cand, 0)] == np.asarray(n_id2)[nearest][:, None])
    t_near = np.where(has, np.take_along_axis(ds["toa_true"].values, col, axis=1)[:, 0], np.nan)
    toa = np.take_along_axis(ds["toa_hat"].values, order, axis=1)
    with np.errstate(invalid="ignore"):
        locked = off & (np.abs(toa - t_near[:, None]) * SPEED_OF_LIGHT_M_S <= LOCK_M)
    return off, pss, locked


def off_air_key_numbers(
    cell: str, rx: str, ok: np.ndarray, off_air: np.ndarray, shares_pss: np.ndarray, locked: np.ndarray, where: str
) -> dict[str, Any]:
    """The selected measurements of RRHs not on the air (:func:`off_air_selections`): their
    share of all selected measurements, and among them the shares that share the nearest
    RRH's PSS and that lie at its delay (null when there are none).

    Parameters
    ----------
    cell, rx : str
        The cell and receiver names.
    ok, off_air, shares_pss, locked : numpy.ndarray of bool
        [n, n_use] the selected slots holding a measurement, and :func:`off_air_selections`.
    where : str
        Text appended to each key's description.

    Returns
    -------
    dict of str to dict
        ``nr.map.<cell>.<rx>.diag.off_air.{frac, pss_frac, locked_frac}`` (1).

    Raises
    ------
    ValueError
        When the arrays differ in shape.
    """
    if not ok.shape == off_air.shape == shares_pss.shape == locked.shape:
        raise ValueError("ok, off_air, shares_pss and locked must share a shape")
    n_ok, n_off = int(ok.sum()), int(off_air.sum())
    p = f"nr.map.{cell}.{rx}.diag.off_air"
    vals = {
        "frac": ("share of the selected measurements of RRHs not on the air (beyond nr.radio.range_m)", n_off, n_ok),
        "pss_frac": (
            "share of the off-air selections sharing their N_ID2 (PSS) with the nearest RRH",
            shares_pss.sum(),
            n_off,
        ),
        "locked_frac": (
            f"share of the off-air selections whose TOA lies within {LOCK_M:g} m of the nearest RRH's delay",
            locked.sum(),
            n_off,
        ),
    }
    return {
        f"{p}.{k}": KeySpec(f"{p}.{k}", "1", f"{d} ({where})").entry(float(a) / b if b else None)
        for k, (d, a, b) in vals.items()
    }
