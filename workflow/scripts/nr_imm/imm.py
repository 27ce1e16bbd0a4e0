"""Adapter: one realization's shards + calibration -> results/nr/imm/{real}.nc
(EKF, IMM and RTS-smoothed EKF on the same measurements; docs/model/nr.md §6)."""

import json
import sys
from pathlib import Path

import numpy as np
import xarray as xr

sys.path.insert(0, str(Path(__file__).parent.parent / "nr"))
from common import read_shards, scenario

from railradio.io import write_dataset
from railradio.nr.bounds import change_epochs
from railradio.nr.dynamics import process_noise, transition
from railradio.nr.imm import ImmConfig, position_nees, q_for_jump, track_filters
from railradio.nr.smoother import rts_smooth
from railradio.nr.tracking import TrackerConfig
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
scn = scenario(smk)
dep, traj = scn.deployment, scn.trajectory
p = dict(smk.params.imm)
rx = p["receiver"]
ds = read_shards(smk.input.shards)
if rx not in [str(r) for r in ds["receiver"].values]:
    raise ValueError(f"nr.imm.receiver = {rx!r} is not among the simulated receivers {ds['receiver'].values.tolist()}")
ds = ds.sel(receiver=rx)
c = json.loads(open(smk.input.calibration, encoding="utf-8").read())[f"{rx}/aod_toa/gate"]
cfg = TrackerConfig.from_record(c, variant="aod_toa", gate=True, gate_prob=smk.params.tracker["gate_prob"])
q_quiet = c["q"] if p["q_quiet"] is None else float(p["q_quiet"])
q_man = q_for_jump(p["delta_a_m_s2"], traj.dt_s)
imm = ImmConfig(q=(q_quiet, q_man), sojourn_s=tuple(p["sojourn_s"]))
log.info("receiver %s, calibration %s; IMM q = %s m2/s5, sojourn %s s", rx, c, imm.q, imm.sojourn_s)
out = track_filters(
    ds, dep.x_m, dep.offset_m, dep.h_bs_m - dep.h_ut_m, traj.dt_s, cfg, imm, strength=smk.params.selection[rx]
)
xs, ps = rts_smooth(out["ekf"]["state"], out["ekf"]["cov"], transition(traj.dt_s), process_noise(traj.dt_s, cfg.q))
runs = {
    "ekf": (out["ekf"]["state"], out["ekf"]["cov"]),
    "imm": (out["imm"]["state"], out["imm"]["cov"]),
    "rts": (xs, ps),
}
x_true = ds["x_true"].values
n = x_true.size
pos_err = np.stack([np.hypot(s[:, 0] - x_true, s[:, 1]) for s, _ in runs.values()])
along = np.stack([s[:, 0] - x_true for s, _ in runs.values()])
nees = np.stack([position_nees(s, P, x_true) for s, P in runs.values()])
for i, f in enumerate(runs):
    log.info("%s: mean error %.3f m, mean NEES %.2f", f, np.nanmean(pos_err[i]), np.nanmean(nees[i]))
ce = change_epochs(traj.phases, traj.dt_s)
acc = np.array([a for _, a in traj.phases])
inside = ce < n
epoch_attrs = {"units": "1", "long_name": "epoch index"}
res = xr.Dataset(
    {
        "pos_err": (("filter", "epoch"), pos_err, {"units": "m", "long_name": "2-D position error at the burst start"}),
        "along_err": (("filter", "epoch"), along, {"units": "m", "long_name": "along-track error x_hat - x_true"}),
        "pos_nees": (
            ("filter", "epoch"),
            nees,
            {"units": "1", "long_name": "2-D position NEES (chi2 with 2 dof if consistent)"},
        ),
        "mode_prob": (("mode", "epoch"), out["imm"]["mu"].T, {"units": "1", "long_name": "IMM mode probability"}),
        "q": (
            ("mode",),
            np.array(imm.q, float),
            {"units": "m2 s-5", "long_name": "white-jerk intensity of the IMM model"},
        ),
        "sojourn_s": (
            ("mode",),
            np.array(imm.sojourn_s, float),
            {"units": "s", "long_name": "mean sojourn time of the IMM mode"},
        ),
        "n_reacquired": (
            ("filter",),
            np.array([out["ekf"]["reacquired"].sum(), out["imm"]["reacquired"].sum(), out["ekf"]["reacquired"].sum()]),
            {"units": "1", "long_name": "re-acquisitions after track loss (RTS: those of its EKF)"},
        ),
        "t": (("epoch",), ds["t"].values, {"units": "s", "long_name": "time"}),
        "x_true": (("epoch",), x_true, {"units": "m", "long_name": "true position"}),
        "a_true": (("epoch",), ds["a_true"].values, {"units": "m s-2", "long_name": "true acceleration"}),
        "change_epoch": (
            ("change",),
            ce[inside],
            {"units": "1", "long_name": "first epoch of a new acceleration phase"},
        ),
        "delta_a": (
            ("change",),
            np.diff(acc)[inside],
            {"units": "m s-2", "long_name": "acceleration jump at the change"},
        ),
    },
    coords={
        "filter": ("filter", list(runs), {"units": "1", "long_name": "tracker"}),
        "mode": ("mode", ["quiet", "manoeuvre"], {"units": "1", "long_name": "IMM model"}),
        "epoch": ("epoch", ds["epoch"].values, epoch_attrs),
        "change": ("change", np.arange(int(inside.sum())), {"units": "1", "long_name": "acceleration change index"}),
    },
)
write_dataset(
    res,
    smk.output[0],
    {"sim": dict(smk.params.sim), "tracker": dict(smk.params.tracker), "imm": p, "calibration": c},
    None,
    title=f"nr IMM and RTS, {dict(smk.wildcards)}",
)
