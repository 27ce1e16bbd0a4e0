"""The reproduction map as data (:mod:`railradio.nr.study.reproduction_map`): its key numbers
``nr.map.<cell>.<receiver>.*`` as one xarray dataset, cell × receiver × claim, each claim's
metric with its block-bootstrap interval and status, every cell described by what it assumes
(M_T, where the data are beamed, the source receiver's template and cell selection) and the
label the map's figure gives it (:func:`railradio.nr.study.map_figures.cell_label`).

    >>> import xarray as xr
    >>> ds = xr.open_dataset("results/nr/reproduction_map.nc")
    >>> ds.status.sel(receiver="source", claim="ekf_mean").to_series()

A receiver a cell does not run (ours in the template/selection cells) is NaN there.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import xarray as xr

from railradio.nr.study.map_diagnostics import ENDFIRE_DEG
from railradio.nr.study.map_figures import cell_label
from railradio.nr.study.reproduction_map import (
    CLAIMS,
    FAILS,
    HOLDS,
    MEASUREMENT_SETS,
    STATUS_NAMES,
    UNRESOLVED,
    cell_receivers,
    default_cell,
    receivers,
)

DIAGNOSTICS = {
    "aod_err_deg.median_endfire": ("aod_err_median_endfire_deg", "deg"),
    "aod_err_deg.median_broadside": ("aod_err_median_broadside_deg", "deg"),
    "frac_endfire": ("frac_endfire", "1"),
    "n_detected.median": ("n_detected_median", "1"),
    "nearest.meas.aod_err_deg.p95": ("nearest_aod_err_p95_deg", "deg"),
    "nearest.meas.toa_err_m.p95": ("nearest_toa_err_p95_m", "m"),
    "nearest.measured_frac": ("nearest_measured_frac", "1"),
    "off_air.frac": ("off_air_frac", "1"),
}
"""Diagnostic key ``nr.map.<cell>.<rx>.diag.<name>`` -> (dataset variable, unit)."""

OTHER_METRICS = {"meas.toa_err_m.frac_lt_5m": ("toa_frac_lt_5m", "1")}
"""Metrics of a cell that are no claim's -> (dataset variable, unit); each with ``_lo``/``_hi``."""


def _value(numbers: Mapping[str, Mapping[str, Any]], key: str) -> float:
    """A key's value (NaN when the key is absent or has none)."""
    e = numbers.get(key)
    v = None if e is None else e.get("value")
    return np.nan if v is None else float(v)


def map_dataset(
    numbers: Mapping[str, Mapping[str, Any]], cells: Mapping[str, Mapping[str, Any]], nr: Mapping[str, Any]
) -> xr.Dataset:
    """The reproduction map's key numbers as a dataset (cell × receiver × claim).

    Parameters
    ----------
    numbers : mapping
        Key numbers (name -> entry with ``value``), containing ``nr.map.<cell>.<rx>.*`` of
        :func:`railradio.nr.study.reproduction_map.cell_key_numbers` and
        ``diagnostic_key_numbers``.
    cells : mapping of str to mapping
        Map cell name -> its whole nr config (:func:`railradio.nr.study.reproduction_map.cells`),
        in the map's order.
    nr : mapping
        The ``nr`` section of the workflow config (its receivers and ``map`` section).

    Returns
    -------
    xarray.Dataset
        ``status`` (1 holds, 0 not resolved, -1 fails), ``value``, ``lo``, ``hi`` (the claim
        metric and its interval, in ``claim_unit``) per (cell, receiver, claim); ``lost_frac``
        per (cell, receiver, tracker); the diagnostics and the other metrics per (cell,
        receiver); cell coordinates ``label``, ``rrh_elements``, ``data_beam``, ``load``,
        ``template``, ``selection``, ``search_range_m``, ``range_m``, ``is_default``; claim coordinates ``claim_label``,
        ``claimed_value``, ``claim_unit``, ``metric``, ``better``. NaN: the receiver was not
        run in that cell.

    Raises
    ------
    ValueError
        When ``cells`` is empty or a cell's status key is missing from ``numbers`` for a
        receiver it runs.
    """
    names = list(cells)
    if not names:
        raise ValueError("cells must name at least one map cell")
    rxs = list(receivers(nr))
    claims = list(CLAIMS)
    shape = (len(names), len(rxs), len(claims))
    out = {v: np.full(shape, np.nan) for v in ("status", "value", "lo", "hi")}
    lost = np.full((len(names), len(rxs), len(MEASUREMENT_SETS)), np.nan)
    extra = {var: np.full(shape[:2], np.nan) for var, _ in (*DIAGNOSTICS.values(), *OTHER_METRICS.values())}
    for var, _ in OTHER_METRICS.values():
        extra |= {f"{var}_{end}": np.full(shape[:2], np.nan) for end in ("lo", "hi")}
    for i, cell in enumerate(names):
        for j, rx in enumerate(rxs):
            if rx not in cell_receivers(cell, dict(nr)):
                continue
            p = f"nr.map.{cell}.{rx}"
            for k, (cname, claim) in enumerate(CLAIMS.items()):
                if f"{p}.claim.{cname}" not in numbers:
                    raise ValueError(f"numbers lack {p}.claim.{cname} (map cell {cell!r}, receiver {rx!r})")
                out["status"][i, j, k] = _value(numbers, f"{p}.claim.{cname}")
                for v, suffix in (("value", ""), ("lo", ".lo"), ("hi", ".hi")):
                    out[v][i, j, k] = _value(numbers, f"{p}.{claim.metric}{suffix}")
            for k, ms in enumerate(MEASUREMENT_SETS):
                lost[i, j, k] = _value(numbers, f"{p}.track.{ms}.lost_frac")
            for key, (var, _) in DIAGNOSTICS.items():
                extra[var][i, j] = _value(numbers, f"{p}.diag.{key}")
            for key, (var, _) in OTHER_METRICS.items():
                extra[var][i, j] = _value(numbers, f"{p}.{key}")
                for end in ("lo", "hi"):
                    extra[f"{var}_{end}"][i, j] = _value(numbers, f"{p}.{key}.{end}")
    return _assemble(out, lost, extra, names, rxs, claims, cells, nr)


def _assemble(out, lost, extra, names, rxs, claims, cells, nr) -> xr.Dataset:
    """The arrays of :func:`map_dataset` with their coordinates and attributes."""
    dims = ("cell", "receiver", "claim")
    flags = (FAILS, UNRESOLVED, HOLDS)
    interval = f"{nr['map']['confidence']:.0%} moving-block-bootstrap interval"
    ds = xr.Dataset(
        {
            "status": (
                dims,
                out["status"],
                {
                    "units": "1",
                    "long_name": "status of the source's claim in the cell",
                    "flag_values": np.array(flags),
                    "flag_meanings": " ".join(STATUS_NAMES[f].replace(" ", "_") for f in flags),
                },
            ),
            "value": (dims, out["value"], {"units": "see claim_unit", "long_name": "the claim's metric, measured"}),
            "lo": (dims, out["lo"], {"units": "see claim_unit", "long_name": f"lower end of the {interval}"}),
            "hi": (dims, out["hi"], {"units": "see claim_unit", "long_name": f"upper end of the {interval}"}),
            "lost_frac": (
                ("cell", "receiver", "tracker"),
                lost,
                {"units": "1", "long_name": "share of the segment's scored epochs on which the EKF is lost"},
            ),
        }
    )
    units = {var: u for var, u in (*DIAGNOSTICS.values(), *OTHER_METRICS.values())}
    for var, arr in extra.items():
        base = var.removesuffix("_lo").removesuffix("_hi")
        ds[var] = (("cell", "receiver"), arr, {"units": units[base], "long_name": _long_name(var)})
    cfgs = [cells[c] for c in names]
    default = default_cell(dict(nr))
    cell_coords = {
        "label": ([cell_label(c) for c in names], "1", "the cell in words (as the map's figure names it)"),
        "rrh_elements": ([c["antenna"]["rrh_elements"] for c in cfgs], "1", "Tx elements per RRH panel M_T"),
        "data_beam": ([c["traffic"]["data_beam"] for c in cfgs], "1", "where the data are beamed (nr.traffic)"),
        "load": ([float(c["traffic"]["load"]) for c in cfgs], "1", "share of slots a non-serving RRH sends data"),
        "template": ([c["receiver"]["template"] for c in cfgs], "1", "the source receiver's correlation template"),
        "selection": ([c["receiver"]["selection"] for c in cfgs], "1", "the source receiver's cell selection"),
        "search_range_m": (
            [
                np.nan if c["receiver"]["search_range_m"] is None else float(c["receiver"]["search_range_m"])
                for c in cfgs
            ],
            "m",
            "the source receiver's search window (NaN: the source's K, the SS-block spacing)",
        ),
        "range_m": ([float(c["radio"]["range_m"]) for c in cfgs], "m", "RRHs on the air within this 2-D distance"),
        "is_default": ([c == default for c in names], "1", "the cell with the main run's settings"),
    }
    claim_coords = {
        "claim_label": ([CLAIMS[c].label for c in claims], "1", "the source's claim"),
        "claimed_value": ([CLAIMS[c].value for c in claims], "see claim_unit", "the value the source claims"),
        "claim_unit": ([CLAIMS[c].unit for c in claims], "1", "unit of the claim's metric"),
        "metric": ([CLAIMS[c].metric for c in claims], "1", "the key-number metric the claim is about"),
        "better": ([CLAIMS[c].better for c in claims], "1", "which side of the value is as good (low, high)"),
    }
    ds = ds.assign_coords(
        cell=("cell", names, {"units": "1", "long_name": "map cell"}),
        receiver=("receiver", rxs, {"units": "1", "long_name": "receiver"}),
        claim=("claim", claims, {"units": "1", "long_name": "source claim"}),
        tracker=("tracker", list(MEASUREMENT_SETS), {"units": "1", "long_name": "EKF measurement set"}),
    )
    for dim, coords in (("cell", cell_coords), ("claim", claim_coords)):
        for name, (vals, unit, long_name) in coords.items():
            ds = ds.assign_coords({name: (dim, vals, {"units": unit, "long_name": long_name})})
    return ds


def _long_name(var: str) -> str:
    """A readable long name for a diagnostic or other-metric variable of :func:`map_dataset`."""
    near = f"{ENDFIRE_DEG:g} deg of the track"
    names = {
        "aod_err_median_endfire_deg": f"median |AOD error| of the selected RRHs within {near}",
        "aod_err_median_broadside_deg": f"median |AOD error| of the selected RRHs beyond {near}",
        "frac_endfire": f"share of the selected RRHs seen within {ENDFIRE_DEG:g} deg of the track direction",
        "n_detected_median": "median number of SS blocks detected per selected RRH",
        "nearest_aod_err_p95_deg": "95th percentile of the |AOD error| of the RRH nearest the train",
        "nearest_toa_err_p95_m": "95th percentile of the |TOA range error| of the RRH nearest the train",
        "nearest_measured_frac": "share of epochs with the RRH nearest the train measured",
        "off_air_frac": "share of the selected measurements of RRHs not on the air (beyond range_m)",
        "toa_frac_lt_5m": "share of (epoch, selected RRH) pairs with a TOA range error below 5 m",
    }
    for end, word in (("_lo", "lower"), ("_hi", "upper")):
        if var.endswith(end):
            return f"{word} end of the interval of: {names[var.removesuffix(end)]}"
    return names[var]
