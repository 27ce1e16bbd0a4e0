"""Adapter: one realization's shards + calibration -> results/nr/imm/{real}.nc
(EKF, IMM and RTS-smoothed EKF on the same measurements; docs/model/nr.md §6)."""

import json

from railradio.io import write_dataset
from railradio.nr.engine.simulate import scenario_from_config
from railradio.nr.study.runs import read_shards, track_imm
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
p = dict(smk.params.imm)
cal = json.loads(open(smk.input.calibration, encoding="utf-8").read())
scn = scenario_from_config(dict(smk.params.sim))
res, c = track_imm(read_shards(smk.input.shards), scn, cal, p, smk.params.tracker, smk.params.selection, log)
write_dataset(
    res,
    smk.output[0],
    {"sim": dict(smk.params.sim), "tracker": dict(smk.params.tracker), "imm": p, "calibration": c},
    None,
    title=f"nr IMM and RTS, {dict(smk.wildcards)}",
)
