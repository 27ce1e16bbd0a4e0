"""Adapter: calibration run -> results/nr/calibration.json (noise levels and q)."""

from railradio.io import write_json
from railradio.nr.engine.simulate import scenario_from_config
from railradio.nr.study.runs import calibrate_receivers, point_model, read_shards
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
p = smk.params
ds = point_model(read_shards(smk.input), p.tracker)
out = calibrate_receivers(ds, scenario_from_config(dict(p.sim)), p.tracker, p.selection, p.measurement_sets, log)
write_json(smk.output[0], out)
