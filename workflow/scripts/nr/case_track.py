"""Adapter: a sensitivity case's estimates (r0) + its calibration -> its tracks (the main run's
tracking on the case's epochs, TOAs with the case's clock errors)."""

import json

from railradio.io import write_dataset
from railradio.nr.engine.simulate import scenario_from_config
from railradio.nr.study.runs import case_estimates, point_model, read_shards, track_receivers
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
p = smk.params
ds = case_estimates(read_shards(smk.input.shards), p.n_epochs, p.seed, 0, p.sync)  # 0: r0
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
