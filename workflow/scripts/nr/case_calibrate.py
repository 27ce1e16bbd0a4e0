"""Adapter: a sensitivity case's calibration run -> its calibration (the main run's
calibration on the case's epochs, TOAs with the case's clock errors)."""

from railradio.io import write_json
from railradio.nr.engine.simulate import scenario_from_config
from railradio.nr.study.runs import calibrate_receivers, case_estimates, point_model, read_shards
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
p = smk.params
ds = case_estimates(read_shards(smk.input), p.n_epochs, p.seed, 1000, p.sync)  # 1000: the calibration run's ID
out = calibrate_receivers(
    point_model(ds, p.tracker), scenario_from_config(dict(p.sim)), p.tracker, p.selection, p.measurement_sets, log
)
write_json(smk.output[0], out)
