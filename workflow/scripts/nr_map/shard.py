"""Adapter: one shard of the map cells' segment or calibration runs ->
results/nr/map/{cell}/estimates/{real}/s{shard}.nc for each cell that owns those bursts; the
cells that differ only in amplitudes or receivers from one synthesis per epoch
(railradio.nr.engine.variants.simulate_cells)."""

import dataclasses

import numpy as np

from railradio.io import write_dataset
from railradio.nr.engine.epochs import shard_epochs, shard_period
from railradio.nr.engine.simulate import calibration_trajectory, scenario_from_config
from railradio.nr.engine.variants import simulate_cells
from railradio.rng import spawn_key
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
sims = dict(zip(smk.params.cells, (dict(s) for s in smk.params.sims), strict=True))
scns = {c: scenario_from_config(s) for c, s in sims.items()}
if smk.params.calibration is not None:  # the cells' own short calibration run
    traj = calibration_trajectory(
        {"calibration": smk.params.calibration, "trajectory": sims[smk.params.cells[0]]["trajectory"]}
    )
    scns = {c: dataclasses.replace(s, trajectory=traj) for c, s in scns.items()}
first, end = (int(e) for e in smk.params.epochs)
period = shard_period(sims[smk.params.cells[0]])
epochs = first + shard_epochs(end - first, int(smk.params.n_shards), int(smk.wildcards.shard), period)
key = spawn_key("nr", int(smk.params.rid))
log.info("map cells %s, %s (key %s): epochs %d..%d", ", ".join(scns), smk.params.real, key, epochs[0], epochs[-1])
results = simulate_cells(scns, np.asarray(epochs), smk.params.seed, key)
for (cell, ds), path in zip(results.items(), smk.output, strict=True):
    title = f"nr map cell {cell}, {smk.params.real}, shard {smk.wildcards.shard}"
    write_dataset(ds, path, sims[cell], key, title=title)
