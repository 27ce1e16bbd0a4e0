"""Adapter: the main run's shards of one realization -> results/nr/fidelity/s{fshard}.nc."""

import numpy as np
import xarray as xr

from railradio.io import read_dataset, write_dataset
from railradio.nr.engine.simulate import scenario_from_config
from railradio.nr.study.fidelity import FidelityRun, check_production, sample_epochs
from railradio.nr.study.fidelity_dataset import to_dataset
from railradio.nr.tracking.bounds import change_epochs
from railradio.rng import spawn_key
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
scn = scenario_from_config(dict(smk.params.sim))
fid = smk.params.fidelity
main = xr.concat(
    [read_dataset(p) for p in smk.input], dim="epoch", data_vars="minimal", coords="minimal", compat="override"
)
_, v, _ = scn.trajectory.state(scn.trajectory.times_s()[: smk.params.n_epochs])
epochs = sample_epochs(
    smk.params.n_epochs, int(fid["n_epochs"]), change_epochs(scn.trajectory.phases, scn.trajectory.dt_s), v
)
mine = epochs[int(smk.wildcards.fshard) :: int(fid["n_shards"])]
key = spawn_key("nr", int(fid["realization"]))
run = FidelityRun(scn, smk.params.seed, key, dict(smk.params.selection))
receivers = ["source"] + [name for name, _, _ in scn.extra_receivers]
results = []
for e in mine:
    row = main.sel(epoch=int(e))
    res = run.epoch(int(e), row["rrh"].values.astype(np.int64), int(row["serving_true"]))
    check_production(res, row, receivers)  # the production path here is the main run's, bit for bit
    results.append(res)
    log.info("epoch %d: %.1f s", e, sum(res["seconds"].values()))
write_dataset(
    to_dataset(results, receivers),
    smk.output[0],
    {"sim": dict(smk.params.sim), "fidelity": dict(fid)},
    key,
    title=f"nr shortcut fidelity, realization {fid['realization']}, shard {smk.wildcards.fshard}",
)
