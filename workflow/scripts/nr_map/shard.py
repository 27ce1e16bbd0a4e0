"""Adapter: one shard of a map cell's segment or its calibration run ->
results/nr/map/{cell}/estimates/{real}/s{shard}.nc."""

import dataclasses

import numpy as np

from railradio.io import write_dataset
from railradio.nr.engine.epochs import shard_epochs, shard_period, simulate_epochs
from railradio.nr.engine.simulate import calibration_trajectory, scenario_from_config
from railradio.rng import spawn_key
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
sim = dict(smk.params.sim)
scn = scenario_from_config(sim)
if smk.params.calibration is not None:  # the cell's own short calibration run
    scn = dataclasses.replace(
        scn, trajectory=calibration_trajectory({"calibration": smk.params.calibration, "trajectory": sim["trajectory"]})
    )
first, end = (int(e) for e in smk.params.epochs)
epochs = first + shard_epochs(end - first, int(smk.params.n_shards), int(smk.wildcards.shard), shard_period(sim))
key = spawn_key("nr", int(smk.params.rid))
log.info("map cell %s, %s (key %s): epochs %d..%d", smk.wildcards.cell, smk.wildcards.real, key, epochs[0], epochs[-1])
ds = simulate_epochs(scn, np.asarray(epochs), smk.params.seed, key)
write_dataset(
    ds,
    smk.output[0],
    sim,
    key,
    title=f"nr map cell {smk.wildcards.cell}, {smk.wildcards.real}, shard {smk.wildcards.shard}",
)
