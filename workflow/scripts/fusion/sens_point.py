"""Adapter: one fusion sensitivity point -> results/sens/fusion/points/{kind}/p{point}.nc."""

from railradio.fusion.sensitivity import point_key, point_params, simulate_sens_point
from railradio.io import write_dataset
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
log = setup_script(smk.log[0])
point = dict(smk.params.point)
params = point_params(point)
# keyed by the point's parameters without the swept value: common random numbers along a sweep
key = point_key(point)
log.info("point %s, spawn key %s", point, key)
ds = simulate_sens_point(params, smk.params.seed, key, smk.params.chunk_positions)
write_dataset(
    ds,
    smk.output[0],
    point,
    key,
    title=f"fusion sensitivity point ({params.kind}): radius={params.radius_m} m, rho={params.rho}",
)
log.info("wrote %s", smk.output[0])
