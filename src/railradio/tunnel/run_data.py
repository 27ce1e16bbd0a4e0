"""The dataset of one train crossing (:func:`railradio.tunnel.simulate.run_train`): truth, the
snapshot fixes and their geometry, the tracks and their errors, the calibration, the Monte
Carlo realizations' KF errors (docs/model/tunnel.md §3-5)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from railradio.tunnel.filters import Tracks
from railradio.tunnel.geometry import Cable, Tunnel
from railradio.tunnel.wideband import cable_model_delay_s


def run_dataset(
    ev, tracks: Tracks, cal, tunnel: Tunnel, cable: Cable, train, propagation: str, measurement: str
) -> xr.Dataset:
    """The run's dataset: truth, snapshot fixes and their geometry, the tracks, the calibration.

    ``ev`` is the evaluation run ``(t, x_head, x_rx, res)``, ``cal`` the calibration
    (``r0_m2``, ``bias_s``), ``train`` the :class:`railradio.tunnel.simulate.Train`."""
    t, x_head, x_rx, res = ev
    kf, kf_var, nis, rigid, pf = tracks.kf, tracks.kf_var, tracks.nis, tracks.rigid, tracks.pf
    bias_s = cal.bias_s
    offs = train.receiver_offsets_m
    k = x_rx.shape[1]
    m = {"units": "m"}
    tr = ("time_s", "receiver")
    return xr.Dataset(
        {
            "x_head_true": ("time_s", x_head, {**m, "long_name": "true head position"}),
            "x_rx_true": (tr, x_rx, {**m, "long_name": "true receiver position"}),
            "snapshot": (tr, res["fix"], {**m, "long_name": f"snapshot fix ({measurement})"}),
            "snapshot_rssi": (tr, res["fix_rssi"], {**m, "long_name": "RSSI-ranging LS fix (separable only)"}),
            "sigma_tdoa": (tr, res["sigma_tdoa"], {**m, "long_name": "TDOA fix standard deviation from its geometry"}),
            "gdop_source": (
                tr,
                res["gdop_source"],
                {"units": "1", "long_name": "GDOP, the source's 2-D formula (source 4.1.1)"},
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
            "r0_m2": cal.r0_m2,
            "wideband_bias_s": bias_s,
        },
    )


def add_errors(ds: xr.Dataset, x_head: np.ndarray, length_m: float) -> None:
    """Head, tail and train errors of every estimator [epoch] [m] (source 4.4.3)."""
    head, tail = x_head, x_head - length_m
    m = {"units": "m"}
    for est in ("kf", "rigid", "pf"):
        eh = np.abs(ds[f"{est}_head"].values - head)
        et = np.abs(ds[f"{est}_tail"].values - tail)
        ds[f"{est}_err_head"] = ("time_s", eh, {**m, "long_name": f"{est} head error"})
        ds[f"{est}_err_tail"] = ("time_s", et, {**m, "long_name": f"{est} tail error"})
        ds[f"{est}_err"] = (
            "time_s",
            np.sqrt((eh**2 + et**2) / 2.0),
            {**m, "long_name": f"{est} train error sqrt((e_head^2 + e_tail^2)/2) (source 4.4.3)"},
        )


def with_realizations(
    ds: xr.Dataset, rep_h: np.ndarray, rep_t: np.ndarray, rep_rigid: np.ndarray | None = None
) -> xr.Dataset:
    """``ds`` with the head and tail KF errors of every Monte Carlo realization [realization,
    epoch] [m] and their train error (and the rigid-train KF's error where given)."""
    m = {"units": "m"}
    rt = ("realization", "time_s")
    ds = ds.assign_coords(
        realization=("realization", np.arange(rep_h.shape[0]), {"units": "1", "long_name": "Monte Carlo realization"})
    )
    ds["rep_err_head"] = (rt, rep_h, {**m, "long_name": "KF head error per realization"})
    ds["rep_err_tail"] = (rt, rep_t, {**m, "long_name": "KF tail error per realization"})
    ds["rep_err"] = (rt, np.sqrt((rep_h**2 + rep_t**2) / 2.0), {**m, "long_name": "KF train error per realization"})
    if rep_rigid is not None:
        ds["rep_err_rigid"] = (rt, rep_rigid, {**m, "long_name": "rigid-train KF error per realization"})
    return ds


def add_snapshot_errors(ds: xr.Dataset, ev, measurement: str) -> None:
    """The snapshot fixes' errors [epoch, receiver] [m] (wideband: also its wrong sides of the feed)."""
    res, x_rx = ev.res, ev.x_rx
    m = {"units": "m"}
    tr = ("time_s", "receiver")
    if measurement == "wideband":
        ds["ambiguity_wrong"] = (
            tr,
            res["ambiguity_wrong"].astype(np.int8),
            {"units": "1", "long_name": "1 where the snapshot fix took the wrong side of the feed (or feed)"},
        )
    ds["snapshot_err"] = (tr, np.abs(res["fix"] - x_rx), {**m, "long_name": "snapshot error"})
    ds["snapshot_rssi_err"] = (tr, np.abs(res["fix_rssi"] - x_rx), {**m, "long_name": "RSSI-LS snapshot error"})
