"""Adapter: one realization's shards + calibration -> results/nr/track/{real}.nc."""

import json
import sys

import numpy as np
import xarray as xr

sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
from common import read_shards, scenario

from railradio.io import write_dataset
from railradio.nr.calibration import measurement_errors
from railradio.nr.measurement import VARIANTS
from railradio.nr.tracking import TrackerConfig, nees_position, track
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
scn = scenario(smk)
dep = scn.deployment
ds = read_shards(smk.input.shards)
if not smk.params.tracker["lever_arm"]:  # the point model: panels' lever arm ignored
    ds = ds.drop_vars("train_panel_x", errors="ignore")
cal = json.loads(open(smk.input.calibration, encoding="utf-8").read())
receivers = [str(r) for r in ds["receiver"].values]
variants = [str(v) for v in smk.params.variants]
n = ds.sizes["epoch"]
err = np.full((len(receivers), len(variants), 2, n), np.nan)
nis = np.full((len(receivers), len(variants), 2, n), np.nan)
nees = np.full((len(receivers), len(variants), 2, n), np.nan)
snap = np.full((len(receivers), len(variants), n), np.nan)
meas_aod = np.full((len(receivers), n, 3), np.nan)
meas_rng = np.full((len(receivers), n, 3), np.nan)
x_true = ds["x_true"].values
for i, rx in enumerate(receivers):
    dsr = ds.sel(receiver=rx)
    meas_aod[i], meas_rng[i] = measurement_errors(dsr, smk.params.selection[str(rx)], flat=False)
    for j, variant in enumerate(variants):
        for g, gate in enumerate((False, True)):
            c = cal[f"{rx}/{variant}/{'gate' if gate else 'nogate'}"]
            cfg = TrackerConfig.from_record(c, variant=variant, gate=gate, gate_prob=smk.params.tracker["gate_prob"])
            out = track(
                dsr,
                dep.x_m,
                dep.offset_m,
                dep.h_bs_m - dep.h_ut_m,
                scn.trajectory.dt_s,
                cfg,
                strength=smk.params.selection[str(rx)],
                snapshot=(g == 0),
            )
            err[i, j, g] = np.hypot(out["state"][:, 0] - x_true, out["state"][:, 1])
            upd = out["n_used"] > 0
            nis[i, j, g, upd] = out["nis"][upd] / (sum(VARIANTS[variant]) * out["n_used"][upd])
            nees[i, j, g] = nees_position(out["state"], out["cov"], x_true) / 2  # scoring only
            if g == 0:
                snap[i, j] = np.hypot(out["snapshot"][:, 0] - x_true, out["snapshot"][:, 1])
            log.info("%s %s gate=%s: mean error %.3f m", rx, variant, gate, np.nanmean(err[i, j, g]))
dims = ("receiver", "variant", "gate", "epoch")
res = xr.Dataset(
    {
        "pos_err": (dims, err, {"units": "m", "long_name": "2-D EKF position error at the burst start"}),
        "nis": (dims, nis, {"units": "1", "long_name": "NIS per measurement dimension (NaN: no update)"}),
        "nees": (
            dims,
            nees,
            {"units": "1", "long_name": "position NEES per dimension (estimate against truth, P_pos)"},
        ),
        "snap_err": (
            ("receiver", "variant", "epoch"),
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
        "x_true": (("epoch",), x_true, {"units": "m", "long_name": "true position"}),
        "a_true": (("epoch",), ds["a_true"].values, {"units": "m s-2", "long_name": "true acceleration"}),
        "sir_best": (("epoch",), ds["sir_best"].values, dict(ds["sir_best"].attrs)),
    },
    coords={
        "receiver": ("receiver", receivers, {"units": "1", "long_name": "receiver variant"}),
        "variant": ("variant", variants, {"units": "1", "long_name": "measurements used by the tracker"}),
        "gate": ("gate", [0, 1], {"units": "1", "long_name": "chi2 innovation gate off/on"}),
        "epoch": ("epoch", ds["epoch"].values, {"units": "1", "long_name": "epoch index"}),
        "slot": ("slot", [0, 1, 2], {"units": "1", "long_name": "measured RRH rank by strength"}),
    },
)
write_dataset(
    res,
    smk.output[0],
    {"sim": dict(smk.params.sim), "tracker": dict(smk.params.tracker), "calibration": cal},
    None,
    title=f"nr tracking, {dict(smk.wildcards)}",
)
