"""Adapter: one fusion sweep point -> results/fusion/points/{sweep}/p{point}.nc."""

from railradio.fusion.montecarlo import point_params, simulate_point
from railradio.io import write_dataset
from railradio.rng import spawn_key, stable_id
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
log = setup_script(smk.log[0])
point = dict(smk.params.point)
params = point_params(point)
# the point's randomness is keyed by its physical parameters, not by its list index
key = spawn_key("fusion", stable_id(point))
log.info("point %s, spawn key %s", point, key)
ds = simulate_point(params, smk.params.seed, key, smk.params.chunk_positions)
write_dataset(
    ds,
    smk.output[0],
    point,
    key,
    title=f"fusion Monte Carlo point: d={params.d_m} m, "
    f"sigma_tdoa={point['sigma_tdoa_us']} us, sigma_aoa={params.sigma_aoa_rad} rad",
)
log.info("wrote %s", smk.output[0])
