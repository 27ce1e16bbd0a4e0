"""The reproduction map of the nr study: where the source's claims hold (config/README.md, `nr.map`).

Source 000 reports, for its receiver, AOD p95 < 1.3°, TOA p95 < 1.6 m, an EKF
(AOD+TOA) mean error of 0.66 m with p95 1.7 m and p99 2.3 m, about 75 % of epochs below
1 m, the TOA-only EKF better than the AOD-only one, and AOD+TOA the best. It leaves open
what these depend on: the number of Tx elements per RRH panel M_T, where the data traffic
is beamed, the correlation template and the rule that picks the "3 RRHs with the largest
power". A **cell** of the map is one such assumption set; every cell runs the same segment
of realization r0 (its own bursts where they differ, the main run's where they do not) and
has its own short calibration run.

Each metric carries a moving-block-bootstrap interval over the segment's epochs (blocks of
``block_epochs``: errors along the track are correlated over an RRH spacing). A claim is
read as the accuracy the source's receiver achieves: it **holds** when the whole interval is
at least as good as the claimed value, **fails** when the whole interval is worse, and is
**not resolved** otherwise. A tracker lost on ≥ 1 % of the epochs (railradio.nr.tracking.loss) has
no all-epoch accuracy: its accuracy claims fail, marked lost. The rankings compare the
mean error clipped at the loss threshold (a lost epoch counts as half the RRH spacing), so
that a lost tracker ranks last instead of having no mean; a ranking holds when the whole
interval of the difference is below 0 and fails when it is at or above 0 (two trackers
lost alike do not rank).

Statuses are key numbers: 1 holds, 0 not resolved, -1 fails.
"""

from __future__ import annotations

import copy
import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from railradio.config import deep_merge, validate_config
from railradio.keynumbers import KeySpec
from railradio.nr.study.block_bootstrap import block_indices, nanpercentile
from railradio.nr.study.workflow import sim_config
from railradio.nr.tracking import loss

HOLDS, UNRESOLVED, FAILS = 1.0, 0.0, -1.0
CELL_KEY = re.compile(r"^nr\.map\.(mt\d+|tpl|win\d+|single)_")
"""A per-cell key of the map (``nr.map.<cell>.*``; the per-receiver counts are not)."""
STATUS_NAMES = {HOLDS: "holds", UNRESOLVED: "not resolved", FAILS: "fails"}


@dataclass(frozen=True)
class Claim:
    """One claim of the source: the metric it is about, the claimed value and which side
    of it is as good ("low": errors, "high": shares); rankings are differences (< 0 holds)."""

    metric: str
    unit: str
    value: float
    better: str
    label: str
    tracker: str | None = None
    """The measurement set whose loss voids the claim (accuracy claims), if any."""


CLAIMS = {
    "aod_p95": Claim("meas.aod_err_deg.p95", "deg", 1.3, "low", "AOD p95 < 1.3°"),
    "toa_p95": Claim("meas.toa_err_m.p95", "m", 1.6, "low", "TOA p95 < 1.6 m"),
    "ekf_mean": Claim("track.aod_toa.err_m.mean", "m", 0.66, "low", "EKF mean 0.66 m", "aod_toa"),
    "ekf_p95": Claim("track.aod_toa.err_m.p95", "m", 1.7, "low", "EKF p95 1.7 m", "aod_toa"),
    "ekf_p99": Claim("track.aod_toa.err_m.p99", "m", 2.3, "low", "EKF p99 2.3 m", "aod_toa"),
    "submeter": Claim("track.aod_toa.frac_submeter", "1", 0.75, "high", "sub-metre ≈ 75 %", "aod_toa"),
    "toa_beats_aod": Claim("rank.toa_minus_aod_m", "m", 0.0, "low", "TOA < AOD"),
    "fusion_best": Claim("rank.fused_minus_best_m", "m", 0.0, "low", "AOD+TOA best"),
}
"""The source's claims, in the order of the map's columns."""

METRICS = {
    "meas.aod_err_deg.p95": ("deg", "95th percentile of |AOD error| of the 3 selected RRHs"),
    "meas.toa_err_m.p95": ("m", "95th percentile of |TOA range error| of the 3 selected RRHs"),
    "meas.toa_err_m.frac_lt_5m": ("1", "share of (epoch, selected RRH) pairs with a TOA range error below 5 m"),
    "track.aod_toa.err_m.mean": ("m", "mean 2-D position error, EKF AOD+TOA (null: lost on >= 1 % of epochs)"),
    "track.aod_toa.err_m.p95": ("m", "95th percentile of the 2-D position error, EKF AOD+TOA (null: lost)"),
    "track.aod_toa.err_m.p99": ("m", "99th percentile of the 2-D position error, EKF AOD+TOA (null: lost)"),
    "track.aod_toa.frac_submeter": ("1", "share of epochs with a 2-D error below 1 m, EKF AOD+TOA (null: lost)"),
    "rank.toa_minus_aod_m": ("m", "clipped mean error of the TOA EKF minus that of the AOD EKF (< 0: TOA better)"),
    "rank.fused_minus_best_m": (
        "m",
        "clipped mean error of the AOD+TOA EKF minus the better single one's (< 0: fusion best)",
    ),
}
"""Every metric of a map cell (unit, description), each with its bootstrap interval."""

MEASUREMENT_SETS = ("aod", "toa", "aod_toa")
"""The trackers every map cell runs per receiver (the rankings need all three)."""


GATED = "_gated"
"""Suffix of a tracker that gates a receiver the map otherwise tracks ungated (``source_gated``)."""


def receivers(nr: dict) -> dict[str, bool]:
    """The map's trackers, each named after the receiver it reads -> whether it is gated:
    the source's receiver as the source tracks it (``source``, no gate) and with our χ² gate
    (``source_gated``, the conditions' gate axis), and ours (every ``extra_receivers``
    entry, gated).

    Parameters
    ----------
    nr : dict
        The ``nr`` section of the workflow config.

    Returns
    -------
    dict of str to bool
        Tracker name -> gated (``source``, ``source_gated``, then the extra receivers in config order).
    """
    return {"source": False, f"source{GATED}": True} | {name: True for name in nr.get("extra_receivers", {})}


def receiver_of(tracker: str) -> str:
    """The receiver whose estimates a map tracker reads: ``source_gated`` -> ``source``.

    Parameters
    ----------
    tracker : str
        A tracker name of :func:`receivers`.

    Returns
    -------
    str
        The receiver name (the tracker's without :data:`GATED`).
    """
    return tracker.removesuffix(GATED)


def window_cell(window_m: float, data: str) -> str:
    """The name of a conditions cell: ``win<metres>_<data>`` (``win2000_none``).

    Parameters
    ----------
    window_m : float
        The source receiver's search window [m] (``nr.receiver.search_range_m``).
    data : str
        The data assumption (a key of ``nr.map.data``).

    Returns
    -------
    str
        The cell's name.
    """
    return f"win{round(float(window_m))}_{data}"


SINGLE_CELL = "single_none"
"""The sanity row of the conditions (``nr.map.conditions.single_rrh``): the nearest RRH alone
in range and no data."""


def single_rrh_range_m(deployment: dict) -> float:
    """The range that keeps the nearest RRH alone in range: its 2-D distance from the track's
    point midway between two RRHs, √((spacing/2)² + offset²) (only that point has two).

    Parameters
    ----------
    deployment : dict
        The nr ``deployment`` section (``spacing_m``, ``offset_m``; m).

    Returns
    -------
    float
        ``nr.radio.range_m`` of the sanity row, m.

    Raises
    ------
    ValueError
        When ``spacing_m`` is not positive or ``offset_m`` is negative.
    """
    spacing, offset = float(deployment["spacing_m"]), float(deployment["offset_m"])
    if not spacing > 0:
        raise ValueError(f"deployment spacing_m must be > 0, got {spacing!r}")
    if not offset >= 0:
        raise ValueError(f"deployment offset_m must be >= 0, got {offset!r}")
    return float(np.hypot(spacing / 2, offset))


def cells(nr: dict, nr_schema: dict) -> dict[str, dict[str, Any]]:
    """Every map cell as a whole nr config (validated): ``mt<M>_<data>`` for each M_T of
    ``map.rrh_elements`` and data assumption of ``map.data``, then ``win<m>_<data>`` for each
    search window of ``map.conditions.windows_m`` and data assumption of
    ``map.conditions.data`` on the main run's M_T, then the sanity row :data:`SINGLE_CELL`
    (``map.conditions.single_rrh``: the main run's settings with the range
    :func:`single_rrh_range_m` and no data), then ``tpl_<t>_sel_<s>`` for the source
    receiver's template × selection on the default bursts (the main run's M_T and the first
    data assumption), except the main config's own pair (the default cell).

    Parameters
    ----------
    nr : dict
        The ``nr`` section of the workflow config (with its ``map`` section).
    nr_schema : dict
        The JSON schema of the ``nr`` section.

    Returns
    -------
    dict of str to dict
        Cell name -> its whole, validated nr config (without ``sensitivity`` and ``map``).

    Raises
    ------
    railradio.config.ConfigError
        From :func:`railradio.config.validate_config` for a cell that breaks the schema.
    """
    mp = nr["map"]
    base = {k: copy.deepcopy(v) for k, v in nr.items() if k not in ("sensitivity", "map")}
    out = {}
    for m in mp["rrh_elements"]:
        for data, traffic in mp["data"].items():
            out[f"mt{m}_{data}"] = {"antenna": {"rrh_elements": m}, "traffic": dict(traffic)}
    m_main = nr["antenna"]["rrh_elements"]
    for w in mp.get("conditions", {}).get("windows_m", []):
        for data in mp["conditions"]["data"]:
            out[window_cell(w, data)] = deep_merge(
                out[f"mt{m_main}_{data}"], {"receiver": {"search_range_m": float(w)}}
            )
    if mp.get("conditions", {}).get("single_rrh", False):
        out[SINGLE_CELL] = {
            "antenna": {"rrh_elements": m_main},
            "radio": {"range_m": single_rrh_range_m(nr["deployment"])},
            "traffic": {"data_beam": "none"},
        }
    default = dict(out[default_cell(nr)])
    for t in mp["templates"]:
        for s in mp["selections"]:
            if (t, s) != (nr["receiver"]["template"], nr["receiver"]["selection"]):
                out[f"tpl_{t}_sel_{s}"] = deep_merge(default, {"receiver": {"template": t, "selection": s}})
    return {name: validate_config(deep_merge(base, o), nr_schema, root=f"nr.map ({name})") for name, o in out.items()}


def default_cell(nr: dict) -> str:
    """The cell with the main run's settings.

    Parameters
    ----------
    nr : dict
        The ``nr`` section of the workflow config (with its ``map`` section).

    Returns
    -------
    str
        ``mt<M>_<data>``: the main run's M_T and the first data assumption of ``map.data``.
    """
    return f"mt{nr['antenna']['rrh_elements']}_{next(iter(nr['map']['data']))}"


def cell_receivers(name: str, nr: dict) -> list[str]:
    """Trackers reported in a cell: a template/selection cell changes the source's
    receiver only (ours equals the default cell's), tracked as the source does; a window
    cell changes the source's receiver only, tracked ungated and gated; every other cell
    (``mt<M>_<data>``, the sanity row) has its own bursts and reports every tracker.

    Parameters
    ----------
    name : str
        The cell name (``mt<M>_<data>``, ``win<m>_<data>``, :data:`SINGLE_CELL` or ``tpl_<t>_sel_<s>``).
    nr : dict
        The ``nr`` section of the workflow config.

    Returns
    -------
    list of str
        The receiver names.
    """
    rx = list(receivers(nr))
    if name.startswith("tpl_"):
        return ["source"]
    return [r for r in rx if receiver_of(r) == "source"] if name.startswith("win") else rx


def burst_config(cfg: dict) -> dict:
    """What a cell's bursts and estimates depend on: its simulation sections without the
    cell selection (applied by the tracker, on the same estimates).

    Parameters
    ----------
    cfg : dict
        A cell's (or the main) nr config.

    Returns
    -------
    dict
        A deep copy of :func:`railradio.nr.study.workflow.sim_config` of ``cfg`` without the
        receivers' ``selection``.
    """
    out = copy.deepcopy(sim_config(cfg))
    out["receiver"].pop("selection", None)
    for v in out.get("extra_receivers", {}).values():
        v.pop("selection", None)
    return out


def burst_owner(name: str, all_cells: dict[str, dict], main_cfg: dict) -> str | None:
    """The cell whose segment shards ``name`` reads: None for the main run's bursts, else
    the first cell (config order) with the same bursts."""
    b = burst_config(all_cells[name])
    if b == burst_config(main_cfg):
        return None
    return next(c for c, cfg in all_cells.items() if burst_config(cfg) == b)


def calibration_owner(name: str, all_cells: dict[str, dict]) -> str:
    """The cell whose calibration shards ``name`` reads (the first with the same bursts)."""
    b = burst_config(all_cells[name])
    return next(c for c, cfg in all_cells.items() if burst_config(cfg) == b)


def shard_paths(cell: str, real: str, all_cells: dict[str, dict], main_cfg: dict, n_main_epochs: int) -> list[str]:
    """Estimate shards a cell reads for its segment (``real="r0"``) or calibration
    (``"cal"``): the main run's r0 shards covering the segment when its bursts are the main
    run's, else those of the first cell with the same bursts.

    Parameters
    ----------
    cell : str
        The cell name.
    real : str
        ``"r0"`` (the segment) or ``"cal"`` (the map's calibration run).
    all_cells : dict of str to dict
        Cell name -> nr config (:func:`cells`), config order.
    main_cfg : dict
        The main ``nr`` config (uses ``n_shards`` and ``map.segment``, ``map.n_shards``).
    n_main_epochs : int
        Evaluation epochs of the main run.

    Returns
    -------
    list of str
        Paths of the estimate shards (netCDF), shard order.
    """
    from railradio.nr.engine.epochs import shard_epochs, shard_period

    if real == "cal":
        return [f"results/nr/map/{calibration_owner(cell, all_cells)}/estimates/cal/s0.nc"]
    owner = burst_owner(cell, all_cells, main_cfg)
    if owner is not None:
        return [f"results/nr/map/{owner}/estimates/r0/s{k}.nc" for k in range(main_cfg["map"]["n_shards"])]
    first, end = main_cfg["map"]["segment"]
    n_sh = main_cfg["n_shards"]
    return [
        f"results/nr/estimates/r0/s{k}.nc"
        for k in range(n_sh)
        if (lambda e: e.size > 0 and e[0] < end and e[-1] >= first)(
            shard_epochs(n_main_epochs, n_sh, k, shard_period(main_cfg))
        )
    ]


def calibration_section(nr: dict) -> dict:
    """The map's calibration run as an nr ``calibration`` section (for
    :func:`railradio.nr.engine.simulate.calibration_trajectory`).

    Parameters
    ----------
    nr : dict
        The ``nr`` section of the workflow config (with its ``map`` section).

    Returns
    -------
    dict
        ``{"epochs": int, "trajectory": {"v0_m_s": start speed [m/s], "phases": [[duration s,
        acceleration m/s²], ...]}}``.
    """
    c = nr["map"]["calibration"]
    return {"epochs": c["epochs"], "trajectory": {"v0_m_s": c["v0_m_s"], "phases": c["phases"]}}


# ---------------------------------------------------------------- claims


def cell_metrics(
    aod_err_rad: np.ndarray,
    range_err_m: np.ndarray,
    pos_err_m: dict[str, np.ndarray],
    spacing_m: float,
    idx: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Every metric of :data:`METRICS` (and each tracker's lost share) of one receiver on
    the epochs ``idx`` ([n_boot, n] resamples; None: the sample itself, shape [1, n]).

    Parameters
    ----------
    aod_err_rad, range_err_m : numpy.ndarray
        AOD [rad] and TOA range [m] errors of the selected RRHs, [n, 3] (NaN: none).
    pos_err_m : dict of str to numpy.ndarray
        Measurement set (``aod``, ``toa``, ``aod_toa``: all three) -> 2-D EKF errors [m], [n].
    spacing_m : float
        RRH spacing [m] (an epoch is lost beyond half of it).
    idx : numpy.ndarray of int or None
        Resampled epochs (:func:`block_indices`).

    Returns
    -------
    dict of str to numpy.ndarray
        Metric -> [n_boot] values ([1] without ``idx``; units of :data:`METRICS`), and
        ``track.<measurements>.lost_frac``.
    """
    n = aod_err_rad.shape[0]
    if idx is None:
        idx = np.arange(n)[None, :]
    b = idx.shape[0]
    out = {
        "meas.aod_err_deg.p95": nanpercentile(np.abs(np.degrees(aod_err_rad[idx])).reshape(b, -1), 95),
        "meas.toa_err_m.p95": nanpercentile(np.abs(range_err_m[idx]).reshape(b, -1), 95),
        "meas.toa_err_m.frac_lt_5m": (np.abs(range_err_m[idx]) < 5.0).reshape(b, -1).mean(axis=1),
    }
    half = spacing_m / 2
    clipped = {}
    for v, e in pos_err_m.items():
        lost = loss.lost_mask(e, spacing_m)
        out[f"track.{v}.lost_frac"] = lost[idx].mean(axis=1)
        clipped[v] = np.where(lost, half, e)[idx].mean(axis=1)
    e = np.where(np.isfinite(pos_err_m["aod_toa"]), pos_err_m["aod_toa"], np.inf)[idx]
    with np.errstate(invalid="ignore"):
        out["track.aod_toa.err_m.mean"] = e.mean(axis=1)
    out["track.aod_toa.err_m.p95"] = np.percentile(e, 95, axis=1)
    out["track.aod_toa.err_m.p99"] = np.percentile(e, 99, axis=1)
    out["track.aod_toa.frac_submeter"] = (e < 1.0).mean(axis=1)
    out["rank.toa_minus_aod_m"] = clipped["toa"] - clipped["aod"]
    out["rank.fused_minus_best_m"] = clipped["aod_toa"] - np.minimum(clipped["aod"], clipped["toa"])
    return out


def status(claim: Claim, lo: float | None, hi: float | None, lost: bool) -> float:
    """:data:`HOLDS`, :data:`FAILS` or :data:`UNRESOLVED` for an interval [lo, hi] of the
    claim's metric (a lost tracker fails its accuracy claims).

    Parameters
    ----------
    claim : Claim
        The claim.
    lo, hi : float or None
        The interval's ends, in the claim's unit (None: no interval, not resolved).
    lost : bool
        Whether the claim's tracker is lost (the claim then fails).

    Returns
    -------
    float
        1.0 holds, 0.0 not resolved, -1.0 fails.
    """
    if lost:
        return FAILS
    if lo is None or hi is None:
        return UNRESOLVED
    if claim.metric.startswith("rank."):  # strictly better; a tie (both lost alike) is not
        return HOLDS if hi < 0 else FAILS if lo >= 0 else UNRESOLVED
    if claim.better == "low":
        return HOLDS if hi <= claim.value else FAILS if lo > claim.value else UNRESOLVED
    return HOLDS if lo >= claim.value else FAILS if hi < claim.value else UNRESOLVED


def _finite(v: float) -> float | None:
    return float(v) if np.isfinite(v) else None


def cell_key_numbers(
    cell: str,
    rx: str,
    aod_err_rad: np.ndarray,
    range_err_m: np.ndarray,
    pos_err_m: dict[str, np.ndarray],
    spacing_m: float,
    rng: np.random.Generator,
    block: int,
    n_boot: int,
    confidence: float,
    where: str,
) -> dict[str, Any]:
    """Key numbers ``nr.map.<cell>.<rx>.*`` of one receiver in one cell: each metric with
    ``.lo``/``.hi`` (the bootstrap interval at ``confidence``) and each claim's status
    ``claim.<name>`` (1 holds, 0 not resolved, -1 fails).

    Parameters
    ----------
    cell, rx : str
        The cell and receiver names.
    aod_err_rad : numpy.ndarray
        [n, 3] AOD errors of the selected RRHs over the segment's scored epochs, rad (NaN: none).
    range_err_m : numpy.ndarray
        [n, 3] TOA range errors of the selected RRHs, m (NaN: none).
    pos_err_m : dict of str to numpy.ndarray
        Measurement set (``aod``, ``toa``, ``aod_toa``) -> [n] 2-D EKF position errors, m.
    spacing_m : float
        RRH spacing, m (an epoch is lost beyond half of it).
    rng : numpy.random.Generator
        Generator of the bootstrap resamples.
    block : int
        Bootstrap block length, epochs (in ``1..n``).
    n_boot : int
        Bootstrap resamples (≥ 1).
    confidence : float
        Confidence of the bootstrap interval, in (0, 1).
    where : str
        Text appended to each key's description.

    Returns
    -------
    dict of str to dict
        Key name -> its JSON entry (:meth:`railradio.keynumbers.KeySpec.entry`).

    Raises
    ------
    ValueError
        When ``block`` is outside ``1..n`` or ``n_boot`` < 1 (:func:`block_indices`).
    """
    point = {k: float(v[0]) for k, v in cell_metrics(aod_err_rad, range_err_m, pos_err_m, spacing_m).items()}
    idx = block_indices(rng, aod_err_rad.shape[0], block, n_boot)
    boot = cell_metrics(aod_err_rad, range_err_m, pos_err_m, spacing_m, idx)
    a = (1 - confidence) / 2
    p = f"nr.map.{cell}.{rx}"
    out: dict[str, Any] = {}
    lost = {v: point[f"track.{v}.lost_frac"] for v in pos_err_m}
    for v, lf in lost.items():
        name = f"{p}.track.{v}.lost_frac"
        out[name] = KeySpec(name, "1", f"share of the segment's scored epochs lost, EKF {v} ({where})").entry(lf)
    interval = {}
    for metric, (unit, desc) in METRICS.items():
        x = boot[metric]
        is_acc = metric.startswith("track.aod_toa.")
        void = is_acc and lost["aod_toa"] >= loss.LOST_FRAC_MAX
        ok = x[np.isfinite(x)]
        lo, hi = (
            (None, None) if void or ok.size < x.size else (float(np.quantile(ok, a)), float(np.quantile(ok, 1 - a)))
        )
        value = loss.accuracy(point[metric], lost["aod_toa"]) if is_acc else _finite(point[metric])
        interval[metric] = (lo, hi)
        se = float(np.std(ok, ddof=1)) if lo is not None and ok.size > 1 else None
        name = f"{p}.{metric}"
        out[name] = KeySpec(name, unit, f"{desc} ({where})").entry(
            value, se, lost_frac=lost["aod_toa"] if is_acc else None
        )
        for end, v in (("lo", lo), ("hi", hi)):
            nm = f"{name}.{end}"
            out[nm] = KeySpec(
                nm,
                unit,
                f"{'lower' if end == 'lo' else 'upper'} end of the {confidence:.0%} "
                f"block-bootstrap interval of {metric} ({where})",
            ).entry(v if v is None or not is_acc else loss.accuracy(v, 0.0))
    for cname, claim in CLAIMS.items():
        lo, hi = interval[claim.metric]
        lost_claim = claim.tracker is not None and lost[claim.tracker] >= loss.LOST_FRAC_MAX
        name = f"{p}.claim.{cname}"
        out[name] = KeySpec(
            name, "1", f"source claim '{claim.label}': 1 holds, 0 not resolved, -1 fails ({where})"
        ).entry(status(claim, lo, hi, lost_claim))
    return out


def summary_key_numbers(numbers: dict[str, Any], cell_names: list[str], nr: dict) -> dict[str, Any]:
    """Per receiver and claim, in how many cells it holds / fails / is not resolved
    (``nr.map.<rx>.<claim>.n_holds`` …) and the number of cells; the sanity row
    (:data:`SINGLE_CELL`, another deployment) is not counted.

    Parameters
    ----------
    numbers : dict
        The cells' key numbers (:func:`cell_key_numbers`), with each claim's status.
    cell_names : list of str
        The map cells.
    nr : dict
        The ``nr`` section of the workflow config.

    Returns
    -------
    dict of str to dict
        Key name -> its JSON entry (:meth:`railradio.keynumbers.KeySpec.entry`).
    """
    out: dict[str, Any] = {}
    for rx in receivers(nr):
        names = [c for c in cell_names if rx in cell_receivers(c, nr) and c != SINGLE_CELL]
        key = f"nr.map.{rx}.n_cells"
        out[key] = KeySpec(key, "1", f"map cells of the {rx} receiver (the sanity row not counted)").entry(
            float(len(names))
        )
        for cname, claim in CLAIMS.items():
            st = [numbers[f"nr.map.{c}.{rx}.claim.{cname}"]["value"] for c in names]
            for code, word in ((HOLDS, "holds"), (FAILS, "fails"), (UNRESOLVED, "unresolved")):
                key = f"nr.map.{rx}.{cname}.n_{word}"
                out[key] = KeySpec(
                    key, "1", f"map cells where the claim '{claim.label}' {STATUS_NAMES[code]} ({rx} receiver)"
                ).entry(float(sum(s == code for s in st)))
    return out
