"""Adapter: one (speed, batch) shard of crossings -> per-handover outcomes (NetCDF)."""

from railradio.handover.cost import best_weights
from railradio.handover.engine import shard_blocks, simulate_blocks
from railradio.handover.params import scenario_from_config
from railradio.handover.sensitivity import affected_policies, apply_case
from railradio.io import read_dataset, write_dataset
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
log = setup_script(smk.log[0])
p = smk.params
case = dict(p.case)
scn = apply_case(scenario_from_config(p.sim), case)
jt = scn.joint
if jt.m is None or jt.alpha is None:
    m, alpha = best_weights(read_dataset(smk.input.cost), jt.wslr)
    scn = scn.with_weights(m if jt.m is None else jt.m, alpha if jt.alpha is None else jt.alpha)
blocks = shard_blocks(p.n_blocks, p.n_batches, int(smk.wildcards.batch))
policies = affected_policies(case, tuple(p.policies))
log.info(
    "speed %s km/h, blocks %s, policies %s, joint (m, alpha) = (%s, %s), case %s",
    p.speed_kmh,
    blocks,
    policies,
    scn.joint.m,
    scn.joint.alpha,
    case or "reference",
)
ds = simulate_blocks(scn, p.speed_kmh, p.seed, blocks, p.runs_per_block, policies)
write_dataset(
    ds,
    smk.output[0],
    {
        "sim": scn.to_dict(),
        "speed_kmh": p.speed_kmh,
        "blocks": [blocks.start, blocks.stop],
        "runs_per_block": p.runs_per_block,
        "case": case,
    },
    None,
    title=f"handover: per-handover outcomes at {p.speed_kmh} km/h, blocks {blocks.start}-{blocks.stop - 1}",
)
log.info("wrote %s", smk.output[0])
