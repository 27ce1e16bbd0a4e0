"""Adapter: the points of one sweep -> results/fusion/sweep_{sweep}.nc."""

from railradio.fusion.montecarlo import SWEEP_PARAMETER, sweep_dataset
from railradio.io import config_of, read_dataset, write_dataset
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
log = setup_script(smk.log[0])
points = [read_dataset(p) for p in smk.input]
ds = sweep_dataset(points, SWEEP_PARAMETER[smk.params.sweep])
write_dataset(
    ds,
    smk.output[0],
    {"sweep": smk.params.sweep, "points": [config_of(p) for p in points]},
    None,
    title=f"fusion sweep over {smk.params.sweep}",
)
log.info("wrote %s", smk.output[0])
