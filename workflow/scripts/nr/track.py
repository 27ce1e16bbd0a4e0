"""Adapter: one realization's shards + calibration -> results/nr/track/{real}.nc."""

import json

from railradio.io import write_dataset
from railradio.nr.engine.simulate import scenario_from_config
from railradio.nr.study.runs import point_model, read_shards, track_receivers
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
p = smk.params
ds = read_shards(smk.input.shards)
cal = json.loads(open(smk.input.calibration, encoding="utf-8").read())
res = track_receivers(
    point_model(ds, p.tracker), scenario_from_config(dict(p.sim)), cal, p.tracker, p.selection, p.measurement_sets, log
)
write_dataset(
    res,
    smk.output[0],
    {"sim": dict(p.sim), "tracker": dict(p.tracker), "calibration": cal},
    None,
    title=f"nr tracking, {dict(smk.wildcards)}",
)
