"""Adapter: calibration run -> results/nr/calibration.json (noise levels and q)."""

import sys

import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
from common import read_shards, scenario

from railradio.io import write_json
from railradio.nr.calibration import calibrate
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
scn = scenario(smk)
dep = scn.deployment
ds = read_shards(smk.input)
if not smk.params.tracker["lever_arm"]:  # the point model: panels' lever arm ignored
    ds = ds.drop_vars("train_panel_x", errors="ignore")
out = {}
for rx in ds["receiver"].values:
    dsr = ds.sel(receiver=rx)
    for variant in smk.params.variants:
        for gate in (False, True):  # each tracker calibrated as it will run
            name = f"{rx}/{variant}/{'gate' if gate else 'nogate'}"
            search = {}
            cfg = calibrate(
                dsr,
                variant,
                dep.x_m,
                dep.offset_m,
                dep.h_bs_m - dep.h_ut_m,
                scn.trajectory.dt_s,
                np.asarray(smk.params.tracker["q_grid"]),
                gate,
                smk.params.selection[str(rx)],
                distance_edges_m=tuple(smk.params.tracker["w_distance_edges_m"]),
                gate_prob=float(smk.params.tracker["gate_prob"]),
                search=search,
            )
            out[name] = cfg.record() | {"q_search": search}
            log.info("%s: %s", name, out[name])
write_json(smk.output[0], out)
