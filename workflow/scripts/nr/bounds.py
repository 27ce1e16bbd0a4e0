"""Adapter: one realization's geometry and link budget -> results/nr/bounds/{real}.nc."""

import json

import numpy as np
import xarray as xr

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.io import write_dataset
from railradio.nr.channel.link import ShadowingMap, link_budget
from railradio.nr.engine.simulate import KEY_SHADOWING, scenario_from_config
from railradio.nr.tracking.bounds import (
    INTEGER_SAMPLE_SIGMA_M,
    burst_e_over_n0,
    change_epochs,
    pcrb_m,
    peb_m,
    toa_crb_s,
)
from railradio.rng import spawn_key
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
scn = scenario_from_config(dict(smk.params.sim))
dep = scn.deployment
dh = dep.h_bs_m - dep.h_ut_m
cal = json.loads(open(smk.input.calibration, encoding="utf-8").read())[smk.params.calibrated]
# the AOD spread the tracker faces: about the AOD model's biases when it has one (one σ for
# every angle bin, railradio.nr.tracking.aod_model.fit), else the single calibrated σ
s_aod = cal["sigma_aod_angle_bins_rad"][0] if cal.get("sigma_aod_angle_bins_rad") else cal["sigma_aod_rad"]
key = spawn_key("nr", int(smk.wildcards.real[1:]))
shadow = ShadowingMap(smk.params.seed, key + (KEY_SHADOWING,), dep, scn.radio)
t = scn.trajectory.times_s()[: smk.params.n_epochs]
x, v, _ = scn.trajectory.state(t)
n = t.size
crb_best = np.full(n, np.nan)
peb = np.full(n, np.nan)
peb_crb = np.full(n, np.nan)
xy_seq, s_seq = [], []
for k in range(n):
    lb = link_budget(float(x[k]), float(v[k]), dep, scn.radio, scn.rrh_array, scn.train_array, shadow)
    s_tau = toa_crb_s(burst_e_over_n0(lb.links))
    best = np.argsort(s_tau)[:3]
    # the best links' RRHs, shifted by the receiving panel's lever arm (0: co-located panels)
    xy = np.stack([dep.x_m[lb.link_rrh[best]] - lb.link_panel_x_m[best], np.full(best.size, dep.offset_m)], axis=1)
    s_r = SPEED_OF_LIGHT_M_S * s_tau[best]
    crb_best[k] = s_r[0]
    peb_crb[k] = peb_m(xy, float(x[k]), dh, s_r, s_aod)
    s_r_q = np.sqrt(s_r**2 + INTEGER_SAMPLE_SIGMA_M**2)  # an integer-sample TOA estimator
    peb[k] = peb_m(xy, float(x[k]), dh, s_r_q, s_aod)
    xy_seq.append(xy)
    s_seq.append(s_r_q / SPEED_OF_LIGHT_M_S)
pcrb = pcrb_m(xy_seq, x, dh, s_seq, s_aod, scn.trajectory.dt_s, cal["q"], np.diag([100.0, 100.0, 1.0, 1.0, 1.0, 1.0]))
# the true motion: constant acceleration within phases, unknown jumps at the changes
pcrb_true = pcrb_m(
    xy_seq,
    x,
    dh,
    s_seq,
    s_aod,
    scn.trajectory.dt_s,
    0.0,
    np.diag([100.0, 100.0, 1.0, 1.0, 1.0, 1.0]),
    reset_epochs=change_epochs(scn.trajectory.phases, scn.trajectory.dt_s),
)
log.info(
    "median TOA CRB %.4f m, median PEB prediction %.3f m, mean PCRB prediction %.3f m (true motion %.3f m)",
    np.median(crb_best),
    np.median(peb),
    np.mean(pcrb),
    np.mean(pcrb_true),
)
ds = xr.Dataset(
    {
        "toa_crb": (
            ("t",),
            crb_best,
            {
                "units": "m",
                "long_name": (
                    "TOA range CRB of the best RRH: its detected blocks against noise and the other RRHs' SS blocks"
                ),
            },
        ),
        "peb_crb": (
            ("t",),
            peb_crb,
            {
                "units": "m",
                "long_name": "snapshot position error predicted from the TOA CRB and the calibration run's AOD spread",
            },
        ),
        "peb": (
            ("t",),
            peb,
            {
                "units": "m",
                "long_name": (
                    "snapshot position error predicted with the integer-sample TOA floor and the "
                    "calibration run's AOD spread"
                ),
            },
        ),
        "pcrb": (
            ("t",),
            pcrb,
            {
                "units": "m",
                "long_name": (
                    "PCRB recursion of the tracked 2-D position with the measured error levels (white-jerk "
                    "model, calibrated q): a prediction"
                ),
            },
        ),
        "pcrb_true_motion": (
            ("t",),
            pcrb_true,
            {
                "units": "m",
                "long_name": (
                    "PCRB recursion for the true motion (constant acceleration, unknown jumps at the known "
                    "phase changes, genie) with the measured error levels: a prediction"
                ),
            },
        ),
    },
    coords={"t": ("t", t, {"units": "s", "long_name": "time"})},
)
write_dataset(
    ds,
    smk.output[0],
    {"sim": dict(smk.params.sim), "calibration": cal},
    key,
    title=f"nr physical limits, realization {smk.wildcards.real}",
)
