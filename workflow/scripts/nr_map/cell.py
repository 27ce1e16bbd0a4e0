"""Adapter: a map cell's segment and calibration estimates -> results/nr/map/{cell}/track.nc
(each receiver's AOD, TOA and AOD+TOA EKF, calibrated on the cell's own calibration run)."""

import numpy as np
import xarray as xr

from railradio.io import write_dataset
from railradio.nr.engine.simulate import scenario_from_config
from railradio.nr.study.map_diagnostics import nearest_errors, off_air_selections
from railradio.nr.study.reproduction_map import MEASUREMENT_SETS, receiver_of
from railradio.nr.study.runs import read_shards
from railradio.nr.tracking.calibration import calibrate, measurement_errors, selected
from railradio.nr.tracking.track import track
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
scn = scenario_from_config(dict(smk.params.sim))
dep, dt = scn.deployment, scn.trajectory.dt_s
first, end = (int(e) for e in smk.params.segment)
seg = read_shards(smk.input.segment)
seg = seg.isel(epoch=np.flatnonzero((seg["epoch"].values >= first) & (seg["epoch"].values < end)))
if seg.sizes["epoch"] != end - first:
    raise ValueError(f"the segment shards hold {seg.sizes['epoch']} of the {end - first} epochs {first}..{end - 1}")
cal_ds = read_shards(smk.input.calibration)
tr = dict(smk.params.tracker)
receivers = {str(k): bool(v) for k, v in dict(smk.params.receivers).items()}
sel = dict(smk.params.selection)
n = seg.sizes["epoch"]
err = np.full((len(receivers), len(MEASUREMENT_SETS), n), np.nan)
along = np.full((len(receivers), len(MEASUREMENT_SETS), n), np.nan)
aod = np.full((len(receivers), n, 3), np.nan)
rng = np.full((len(receivers), n, 3), np.nan)
aod_true = np.full((len(receivers), n, 3), np.nan)
n_det = np.zeros((len(receivers), n, 3), dtype=np.int64)
near = np.full((2, len(receivers), n), np.nan)  # the nearest RRH's AOD [rad] and range [m] errors
off_air = np.zeros((3, len(receivers), n, 3), dtype=bool)  # off-air selections, sharing the PSS, locked
cal = {}
for i, (name, gate) in enumerate(receivers.items()):
    rx = receiver_of(name)  # source_gated: the source's estimates, gated
    dsr, calr = seg.sel(receiver=rx), cal_ds.sel(receiver=rx)
    aod[i], rng[i] = measurement_errors(dsr, sel[rx], flat=False)
    order, ok = selected(dsr, sel[rx])  # the same RRHs: their truth and detections
    aod_true[i] = np.where(ok, np.take_along_axis(dsr["aod_true"].values, order, axis=1), np.nan)
    n_det[i] = np.where(ok, np.take_along_axis(dsr["n_detected"].values, order, axis=1), 0)
    near[:, i] = nearest_errors(dsr, dep.x_m)  # scoring only
    off_air[:, i] = off_air_selections(
        dsr, order, ok, dep.x_m, dep.offset_m, float(smk.params.sim["radio"]["range_m"]), dep.n_id()[1]
    )
    for j, measurements in enumerate(MEASUREMENT_SETS):
        search = {}
        cfg = calibrate(
            calr,
            measurements,
            dep.x_m,
            dep.offset_m,
            dep.h_bs_m - dep.h_ut_m,
            dt,
            np.asarray(tr["q_grid"]),
            gate,
            sel[rx],
            gate_prob=float(tr["gate_prob"]),
            search=search,
            start_speed_sigma_m_s=float(smk.params.start_speed_sigma_m_s),
            aod_angle_edges_rad=tuple(np.radians(tr["aod_angle_edges_deg"])),
        )
        cal[f"{name}/{measurements}"] = cfg.record() | {"gate": gate, "q_search": search}
        out = track(dsr, dep.x_m, dep.offset_m, dep.h_bs_m - dep.h_ut_m, dt, cfg, strength=sel[rx], snapshot=False)
        along[i, j] = out["state"][:, 0] - seg["x_true"].values  # scoring only (the track: y = 0)
        err[i, j] = np.hypot(along[i, j], out["state"][:, 1])
        log.info("%s %s (gate %s): q %.3g, mean error %.3f m", name, measurements, gate, cfg.q, np.nanmean(err[i, j]))
res = xr.Dataset(
    {
        "pos_err": (("receiver", "measurements", "epoch"), err, {"units": "m", "long_name": "2-D EKF position error"}),
        "along_err": (
            ("receiver", "measurements", "epoch"),
            along,
            {"units": "m", "long_name": "signed along-track EKF error x_est - x_true"},
        ),
        "aod_err": (
            ("receiver", "epoch", "slot"),
            aod,
            {"units": "rad", "long_name": "AOD error of the 3 selected RRHs (NaN: not detected)"},
        ),
        "range_err": (
            ("receiver", "epoch", "slot"),
            rng,
            {"units": "m", "long_name": "TOA range error of the 3 selected RRHs (NaN: not detected)"},
        ),
        "aod_true": (
            ("receiver", "epoch", "slot"),
            aod_true,
            {"units": "rad", "long_name": "true AOD of the 3 selected RRHs (scoring)"},
        ),
        "n_detected": (
            ("receiver", "epoch", "slot"),
            n_det,
            {"units": "1", "long_name": "SS blocks detected of the 3 selected RRHs"},
        ),
        "nearest_aod_err": (
            ("receiver", "epoch"),
            near[0],
            {"units": "rad", "long_name": "AOD error of the RRH nearest the train (NaN: not measured)"},
        ),
        "nearest_range_err": (
            ("receiver", "epoch"),
            near[1],
            {"units": "m", "long_name": "TOA range error of the RRH nearest the train (NaN: not measured)"},
        ),
        "selected_off_air": (
            ("receiver", "epoch", "slot"),
            off_air[0],
            {"units": "1", "long_name": "selected RRH not on the air (beyond radio.range_m)"},
        ),
        "selected_off_air_pss": (
            ("receiver", "epoch", "slot"),
            off_air[1],
            {"units": "1", "long_name": "off-air selected RRH sharing its N_ID2 (PSS) with the nearest RRH"},
        ),
        "selected_off_air_locked": (
            ("receiver", "epoch", "slot"),
            off_air[2],
            {"units": "1", "long_name": "off-air selected RRH whose TOA lies at the nearest RRH's delay"},
        ),
        "t": (("epoch",), seg["t"].values, {"units": "s", "long_name": "time"}),
        "v_true": (("epoch",), seg["v_true"].values, {"units": "m s-1", "long_name": "true speed"}),
        "gated": (
            ("receiver",),
            np.array(list(receivers.values())),
            {"units": "1", "long_name": "the receiver's trackers are gated"},
        ),
    },
    coords={
        "receiver": (
            "receiver",
            list(receivers),
            {"units": "1", "long_name": "tracker: the receiver read, _gated when gated"},
        ),
        "measurements": (
            "measurements",
            list(MEASUREMENT_SETS),
            {"units": "1", "long_name": "measurements used by the tracker"},
        ),
        "epoch": ("epoch", seg["epoch"].values, {"units": "1", "long_name": "epoch index of r0"}),
        "slot": ("slot", [0, 1, 2], {"units": "1", "long_name": "selected RRH rank by strength"}),
    },
)
write_dataset(
    res,
    smk.output[0],
    {"sim": dict(smk.params.sim), "tracker": tr, "calibration": cal},
    None,
    title=f"nr map cell {smk.wildcards.cell}: tracks on the segment",
)
