"""Rates and means per policy and speed from the per-handover shards (docs/model/handover.md §7).

Definitions [ours]: success = the handover completed (at any permitted attempt);
interruption = 1 − success; ping-pong = a successful handover followed by a command back
to the previous cell within the window, over all node crossings; delay = first command to
completion incl. retries (successful handovers); delay_all = first command to completion over
every handover, a failed one's re-establishment included; delay_trigger = the same from the
trigger (A3: the start of its time-to-trigger); RSRP-GAP = |serving − target| true
local-mean power at completion.  Intervals: Wilson with the clustered effective sample size
(:mod:`railradio.stats`).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from railradio.stats import clustered_mean, clustered_rate

RATES = ("success", "pingpong", "retried")
STAGE_RATES = ("too_late", "too_early", "wrong_cell", "other_rlf", "t310_at_command")
"""Per-handover shares of the ``stages`` rule's outcome classes (TS 36.300 §22.4.2.2) and of
commands that came while the serving link's T310 ran (NaN under the other rules)."""
MEANS = ("delay_ms", "delay_all_ms", "delay_trigger_ms", "rsrp_gap_db", "attempts")
QUANTILES = {"interruption_ms_median": 0.5, "interruption_ms_p95": 0.95}
"""Quantiles of the command-to-completion time over every handover (``delay_all``, a failed
handover's re-establishment included): the interruption operators count."""


def policy_metrics(ds: xr.Dataset, policy: str, level: float = 0.95) -> dict[str, float]:
    """Metrics of one policy from a per-handover dataset (variables ``<policy>__<name>``).

    Parameters
    ----------
    ds : xarray.Dataset
        Per-handover outcomes over (``run``, ``node``) of
        :func:`railradio.handover.engine.simulate_blocks` (shards concatenated along ``run``).
    policy : str
        Policy name, e.g. ``joint``, ``a3`` or ``distance``.
    level : float, optional
        Confidence level of the Wilson intervals, in (0, 1) (default 0.95).

    Returns
    -------
    dict of str to float
        For the rates ``success``, ``pingpong``, ``retried`` [1]: the rate and ``_se``,
        ``_lo``, ``_hi`` (interval), ``_neff`` (effective sample size); for the means
        ``delay_ms``, ``delay_all_ms``, ``delay_trigger_ms`` [ms], ``rsrp_gap_db`` [dB]
        (of the absolute RSRP-GAP) and ``attempts`` [1]: the mean and ``_se``; ``n_handovers`` and
        ``n_runs`` [1].

    Raises
    ------
    ValueError
        If ``level`` is not in (0, 1).
    KeyError
        If a variable ``<policy>__<name>`` is missing.
    """
    v = {
        name: ds[f"{policy}__{name}"].values
        for name in ("success", "pingpong", "attempts", "delay_s", "delay_all_s", "delay_trigger_s", "rsrp_gap_db")
    }
    out: dict[str, float] = {}
    events = {"success": v["success"], "pingpong": v["pingpong"], "retried": v["attempts"] > 1}
    for name, e in events.items():
        r = clustered_rate(np.asarray(e, dtype=float), level)
        out.update(
            {
                name: r["p"],
                f"{name}_se": r["se"],
                f"{name}_lo": r["lo"],
                f"{name}_hi": r["hi"],
                f"{name}_neff": r["n_eff"],
            }
        )
    if f"{policy}__failure_kind" in ds:
        from railradio.handover.stages import OTHER_RLF, TOO_EARLY, TOO_LATE, WRONG_CELL

        kind = ds[f"{policy}__failure_kind"].values
        stage_events = {
            "too_late": kind == TOO_LATE,
            "too_early": kind == TOO_EARLY,
            "wrong_cell": kind == WRONG_CELL,
            "other_rlf": kind == OTHER_RLF,
            "t310_at_command": ds[f"{policy}__t310_at_command"].values > 0,
        }
        for name, e in stage_events.items():
            r = clustered_rate(np.asarray(e, dtype=float), level)
            out.update({name: r["p"], f"{name}_se": r["se"], f"{name}_lo": r["lo"], f"{name}_hi": r["hi"]})
            out[f"{name}_neff"] = r["n_eff"]
    else:
        for name in STAGE_RATES:
            out.update({name + sfx: float("nan") for sfx in ("", "_se", "_lo", "_hi", "_neff")})
    for name, q in QUANTILES.items():
        out[name] = float(np.quantile(1e3 * v["delay_all_s"], q))
    out["n_handovers"] = float(v["success"].size)
    out["n_runs"] = float(v["success"].shape[0])
    for name, values in (
        ("delay_ms", 1e3 * v["delay_s"]),
        ("delay_all_ms", 1e3 * v["delay_all_s"]),
        ("delay_trigger_ms", 1e3 * v["delay_trigger_s"]),
        ("rsrp_gap_db", np.abs(v["rsrp_gap_db"])),
        ("attempts", v["attempts"].astype(float)),
    ):
        m = clustered_mean(values)
        out[name], out[f"{name}_se"] = m["mean"], m["se"]
    return out


UNITS = {
    "success": ("1", "handover success rate"),
    "pingpong": ("1", "ping-pong rate (return within the window)"),
    "retried": ("1", "share of handovers needing a second attempt"),
    "delay_ms": ("ms", "mean handover delay (command to completion, successful)"),
    "delay_all_ms": ("ms", "mean command-to-completion time, all handovers (re-establishment included)"),
    "delay_trigger_ms": ("ms", "mean trigger-to-completion time, all handovers"),
    "rsrp_gap_db": ("dB", "mean |RSRP-GAP| at completion"),
    "attempts": ("1", "mean execution attempts"),
    "too_late": ("1", "too-late handovers: the serving side failed, re-established in the target"),
    "too_early": ("1", "too-early handovers: access or the new link failed, re-established in the source"),
    "wrong_cell": ("1", "handovers to a wrong cell (none can happen with two cells)"),
    "other_rlf": ("1", "failures re-established in the cell that failed (not mobility failures)"),
    "t310_at_command": ("1", "commands that came while the serving link's T310 ran"),
    "interruption_ms_median": ("ms", "median command-to-completion time, all handovers"),
    "interruption_ms_p95": ("ms", "95th percentile of the command-to-completion time, all handovers"),
    "n_handovers": ("1", "node handovers simulated"),
    "n_runs": ("1", "train crossings simulated"),
}


def _attrs(name: str) -> dict[str, str]:
    for base, (units, long_name) in UNITS.items():
        if name == base:
            return {"units": units, "long_name": long_name}
        for suffix, what in (
            ("_se", "standard error"),
            ("_lo", "95% CI lower bound"),
            ("_hi", "95% CI upper bound"),
            ("_neff", "effective sample size"),
        ):
            if name == base + suffix:
                return {"units": units if suffix != "_neff" else "1", "long_name": f"{long_name}: {what}"}
    raise KeyError(name)


def metrics_dataset(
    metrics: dict[str, dict[str, dict[str, float]]], dim: str, dim_attrs: dict, coord_values: list
) -> xr.Dataset:
    """Dataset over (policy, ``dim``) from metrics[group][policy][name], groups in insertion
    order labelled by ``coord_values``.

    Parameters
    ----------
    metrics : dict
        metrics[group][policy][name] -> value, from :func:`policy_metrics`; every group holds
        the same policies and names as the first.
    dim : str
        Name of the group dimension, e.g. ``speed_kmh`` or ``case``.
    dim_attrs : dict
        Attributes (``units``, ``long_name``) of the ``dim`` coordinate.
    coord_values : list
        One label per group (e.g. speeds in km/h), in the order of ``metrics``.

    Returns
    -------
    xarray.Dataset
        One variable per metric name over (``policy``, ``dim``) with ``units`` and
        ``long_name`` from :data:`UNITS` (e.g. ``success`` [1], ``delay_ms`` [ms],
        ``rsrp_gap_db`` [dB], their ``_se``/``_lo``/``_hi``/``_neff``); coordinates
        ``policy`` and ``dim``.

    Raises
    ------
    ValueError
        If ``coord_values`` does not label every group.
    KeyError
        If a metric name is not in :data:`UNITS` (with its suffixes).
    """
    keys = list(metrics)
    if len(keys) != len(coord_values):
        raise ValueError("coord_values must label every group of metrics")
    policies = list(metrics[keys[0]])
    names = list(metrics[keys[0]][policies[0]])
    data = {
        name: (("policy", dim), np.array([[metrics[c][p][name] for c in keys] for p in policies]), _attrs(name))
        for name in names
    }
    return xr.Dataset(
        data,
        coords={
            "policy": ("policy", policies, {"units": "1", "long_name": "handover policy"}),
            dim: (dim, coord_values, dim_attrs),
        },
    )
