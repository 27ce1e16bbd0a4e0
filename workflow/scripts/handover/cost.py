"""Adapter: the cost grid of (m, alpha) -> results/handover/cost.nc (source Fig. 4)."""

import numpy as np

from railradio.handover.cost import cost_grid
from railradio.handover.params import scenario_from_config
from railradio.io import write_dataset
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
log = setup_script(smk.log[0])
sim, cc = smk.params.sim, smk.params.cost
scn = scenario_from_config(sim)
alphas = np.round(np.arange(cc["alpha_min"], cc["alpha_max"] + 1e-9, cc["alpha_step"]), 6)
log.info(
    "cost grid at %s km/h: %d blocks x %d runs, m %s, %d alphas",
    cc["speed_kmh"],
    cc["n_blocks"],
    smk.params.runs_per_block,
    cc["m_values"],
    alphas.size,
)
ds = cost_grid(
    scn,
    cc["speed_kmh"],
    smk.params.seed,
    cc["n_blocks"],
    smk.params.runs_per_block,
    list(cc["m_values"]),
    alphas,
    cc["full_grid_max_m"],
    cc["full_grid_step"],
)
write_dataset(
    ds,
    smk.output[0],
    {"sim": sim, "cost": cc, "runs_per_block": smk.params.runs_per_block},
    None,
    title="handover: cost J(m, alpha) of the joint decision",
)
log.info(
    "best (m, alpha): %s",
    dict(zip(ds["wslr"].values, zip(ds["best_m"].values, ds["best_alpha"].values, strict=True), strict=True)),
)
