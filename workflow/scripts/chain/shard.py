"""Adapter: one shard of chained crossings (every position input, every policy) -> NetCDF."""

from railradio.chain.nr_error import series_from_runs
from railradio.chain.params import params_from_config
from railradio.chain.sim import simulate_blocks
from railradio.handover.cost import best_weights
from railradio.handover.engine import shard_blocks
from railradio.handover.params import scenario_from_config
from railradio.io import read_dataset, write_dataset
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
log = setup_script(smk.log[0])
p = smk.params
ch = params_from_config(dict(p.chain))
scn = scenario_from_config(p.sim)
jt = scn.joint
if jt.m is None or jt.alpha is None:
    m, alpha = best_weights(read_dataset(smk.input.cost), jt.wslr)
    scn = scn.with_weights(m if jt.m is None else jt.m, alpha if jt.alpha is None else jt.alpha)
runs = [read_dataset(f) for f in smk.input.nr]
nr = {f: series_from_runs(runs, f, ch.speed_kmh, ch.speed_halfwidth_kmh, ch.outage_drift_m_s) for f in ch.nr_filters}
blocks = shard_blocks(ch.n_blocks, p.n_batches, int(smk.wildcards.batch))
log.info(
    "speed %s km/h, blocks %s, joint (m, alpha) = (%s, %s), nr epochs %s",
    ch.speed_kmh,
    blocks,
    scn.joint.m,
    scn.joint.alpha,
    {f: s.n_epochs for f, s in nr.items()},
)
ds = simulate_blocks(scn, ch.speed_kmh, p.seed, blocks, p.runs_per_block, ch.sigmas_m, ch.gm_corr_s, nr)
write_dataset(
    ds,
    smk.output[0],
    {
        "sim": scn.to_dict(),
        "chain": ch.to_dict(),
        "blocks": [blocks.start, blocks.stop],
        "runs_per_block": p.runs_per_block,
    },
    None,
    title=f"chain: handover outcomes per position input, blocks {blocks.start}-{blocks.stop - 1}",
)
log.info("wrote %s", smk.output[0])
