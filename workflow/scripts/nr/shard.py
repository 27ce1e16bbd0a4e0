"""Adapter: one track shard of realization r<i> or of the calibration run (params.real) ->
results/nr/estimates/{real}/s{shard}.nc (nr_shard, nr_cal_shard, nr_case_shard)."""

import dataclasses

from railradio.io import write_dataset
from railradio.nr.engine.epochs import shard_epochs, shard_period, simulate_epochs
from railradio.nr.engine.simulate import calibration_trajectory, scenario_from_config
from railradio.rng import spawn_key
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
scn = scenario_from_config(dict(smk.params.sim))
real = smk.params.real  # r<i> or cal
if real == "cal":  # the calibration run's own trajectory
    scn = dataclasses.replace(
        scn,
        trajectory=calibration_trajectory(
            {"calibration": smk.params.calibration, "trajectory": smk.params.sim["trajectory"]}
        ),
    )
# realization r<i> -> ID i; the calibration run has its own ID (another seed key)
rid = 1000 if real == "cal" else int(real[1:])
key = spawn_key("nr", rid)
epochs = shard_epochs(smk.params.n_epochs, smk.params.n_shards, int(smk.wildcards.shard), shard_period(smk.params.sim))
log.info("realization %s (key %s): epochs %d..%d", real, key, epochs[0], epochs[-1])
ds = simulate_epochs(scn, epochs, smk.params.seed, key)
write_dataset(
    ds,
    smk.output[0],
    dict(smk.params.sim),
    key,
    title=f"nr per-cell estimates, realization {real}, shard {smk.wildcards.shard}",
)
