"""The fidelity target's per-epoch results as an :class:`xarray.Dataset` (one shard's
``results/nr/fidelity/s{k}.nc``) and back to the arrays its measures read."""

from __future__ import annotations

import numpy as np

from railradio.nr.study.fidelity_stats import stack

_VR = ("path", "receiver", "epoch", "cand")
_DIMS = ("epoch", "cand")


def to_dataset(results: list[dict], receivers: list[str]):
    """The per-epoch results of :meth:`railradio.nr.study.fidelity.FidelityRun.epoch` as an
    :class:`xarray.Dataset`.

    Parameters
    ----------
    results : list of dict
        Per-epoch results of :meth:`railradio.nr.study.fidelity.FidelityRun.epoch` (same paths,
        receivers and candidate count).
    receivers : list of str
        Receiver names.

    Returns
    -------
    xarray.Dataset
        Per (``path``, ``receiver``, ``epoch``, ``cand``): ``detected`` (per ``block``), ``selected``,
        ``toa`` [full-rate samples], ``aod`` [rad]; the truth (``d3d`` [m], ``aod_true`` [rad],
        ``in_range``), per-path costs (``seconds`` [s]) and the detector-setting variables.
    """
    import xarray as xr

    paths = list(results[0]["decisions"])
    settings = list(results[0]["detector"])
    st = stack(results, receivers)
    ep = np.array([r["epoch"] for r in results])
    n_b = st[paths[0]][receivers[0]]["detected"].shape[-1]
    n_c = results[0]["cand"].size
    ds = xr.Dataset(
        _decision_vars(st, paths, receivers)
        | _truth_vars(results)
        | _cost_and_detector_vars(results, paths, settings, receivers),
        coords={
            "path": ("path", paths, {"units": "1", "long_name": "synthesis and receiver path"}),
            "receiver": ("receiver", receivers, {"units": "1", "long_name": "receiver"}),
            "epoch": ("epoch", ep, {"units": "1", "long_name": "epoch of the main run's realization"}),
            "cand": ("cand", np.arange(n_c), {"units": "1", "long_name": "place in the neighbour list"}),
            "block": ("block", np.arange(n_b), {"units": "1", "long_name": "SS block"}),
            "setting": ("setting", settings, {"units": "1", "long_name": "our detector with one constant changed"}),
        },
    )
    return ds


def _decision_vars(st: dict, paths: list[str], receivers: list[str]) -> dict:
    """Every path's decisions per receiver (:func:`railradio.nr.study.fidelity_stats.stack`'s arrays)."""

    def per(key):
        return np.stack([np.stack([st[v][r][key] for r in receivers]) for v in paths])

    return {
        "detected": (
            _VR + ("block",),
            per("detected").astype(np.int8),
            {"units": "1", "long_name": "SS block detected"},
        ),
        "selected": (
            _VR,
            per("selected").astype(np.int8),
            {"units": "1", "long_name": "candidate among the receiver's selected cells"},
        ),
        "toa": (
            _VR,
            per("toa"),
            {"units": "1", "long_name": "TOA estimate in full-rate samples (NaN: nothing detected)"},
        ),
        "aod": (_VR, per("aod"), {"units": "rad", "long_name": "AOD estimate (NaN: nothing detected)"}),
    }


def _truth_vars(results: list[dict]) -> dict:
    """The candidate lists and the truth, for scoring only."""
    t = {k: np.stack([r["truth"][k] for r in results]) for k in ("d3d", "aod", "in_range")}
    s = {k: np.array([r["truth"][k] for r in results], float) for k in ("x", "v", "a", "sir_db", "n_links")}
    return {
        "rrh": (
            _DIMS,
            np.stack([r["cand"] for r in results]),
            {"units": "1", "long_name": "candidate RRH (the main run's neighbour list)"},
        ),
        "d3d": (_DIMS, t["d3d"], {"units": "m", "long_name": "true 3-D distance (scoring only)"}),
        "aod_true": (_DIMS, t["aod"], {"units": "rad", "long_name": "true AOD (scoring only)"}),
        "in_range": (
            _DIMS,
            t["in_range"].astype(np.int8),
            {"units": "1", "long_name": "the candidate transmits (within nr.radio.range_m)"},
        ),
        "x_true": (("epoch",), s["x"], {"units": "m", "long_name": "true train position"}),
        "v_true": (("epoch",), s["v"], {"units": "m s-1", "long_name": "true speed"}),
        "a_true": (("epoch",), s["a"], {"units": "m s-2", "long_name": "true acceleration"}),
        "sir_best": (
            ("epoch",),
            s["sir_db"],
            {"units": "dB", "long_name": "strongest RRH's power over the sum of the others"},
        ),
        "n_links": (("epoch",), s["n_links"], {"units": "1", "long_name": "RRHs in range (synthesized)"}),
    }


def _cost_and_detector_vars(results: list[dict], paths: list[str], settings: list[str], receivers: list[str]) -> dict:
    """Each path's wall time, our detector's constants one at a time and the interference-only
    false alarms."""
    return {
        "seconds": (
            ("path", "epoch"),
            np.array([[r["seconds"].get(v, np.nan) for r in results] for v in paths]),
            {"units": "s", "long_name": "wall time of the path's synthesis and correlation (one core)"},
        ),
        "det_toa": (
            ("setting",) + _DIMS,
            np.stack([np.stack([r["detector"][k]["toa"] for r in results]) for k in settings]),
            {"units": "1", "long_name": "our receiver's TOA [full-rate samples] with one detector constant changed"},
        ),
        "det_n_detected": (
            ("setting",) + _DIMS,
            np.stack([np.stack([r["detector"][k]["n_detected"] for r in results]) for k in settings]),
            {"units": "1", "long_name": "our receiver's detected blocks with one detector constant changed"},
        ),
        "fa_interference": (
            ("receiver", "epoch"),
            np.array([[r["interference_false_alarms"][rx] for r in results] for rx in receivers]),
            {
                "units": "1",
                "long_name": "blocks detected for the anchor cell's PCI with the anchor silent (of n_blocks)",
            },
        ),
    }


def from_dataset(ds) -> tuple[dict, dict]:
    """``(stacked, truth)`` for :func:`railradio.nr.study.fidelity_stats.summarize` from a
    (concatenated) fidelity dataset.

    Parameters
    ----------
    ds : xarray.Dataset
        A fidelity dataset (:func:`to_dataset`, possibly several concatenated along ``epoch``).

    Returns
    -------
    stacked : dict
        Path -> receiver -> ``detected``, ``selected`` (bool), ``toa`` [full-rate samples],
        ``aod`` [rad] arrays.
    truth : dict
        ``d3d`` [m], ``aod`` [rad] and ``in_range`` (bool), [epoch, cand].
    """
    stacked = {}
    for v in ds["path"].values:
        stacked[str(v)] = {}
        for r in ds["receiver"].values:
            sel = ds.sel(path=v, receiver=r)
            stacked[str(v)][str(r)] = {
                "detected": sel["detected"].values.astype(bool),
                "selected": sel["selected"].values.astype(bool),
                "toa": sel["toa"].values,
                "aod": sel["aod"].values,
            }
    truth = {"d3d": ds["d3d"].values, "aod": ds["aod_true"].values, "in_range": ds["in_range"].values.astype(bool)}
    return stacked, truth
