"""Adapter: the points of one sensitivity sweep -> results/sens/fusion/sweep_{kind}.nc."""

from railradio.fusion.sensitivity import sens_sweep_dataset
from railradio.io import config_of, read_dataset, write_dataset
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
log = setup_script(smk.log[0])
points = [read_dataset(p) for p in smk.input]
ds = sens_sweep_dataset(points, smk.params.kind)
write_dataset(
    ds,
    smk.output[0],
    {"kind": smk.params.kind, "points": [config_of(p) for p in points]},
    None,
    title=f"fusion sensitivity sweep: {smk.params.kind}",
)
log.info("wrote %s", smk.output[0])
