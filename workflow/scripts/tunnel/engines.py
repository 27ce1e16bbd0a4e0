"""Adapter: image method vs SBR (square and circle) -> results/tunnel/engines.nc."""

from railradio.io import read_dataset, write_dataset
from railradio.tunnel.engine_checks import make_engines
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
write_dataset(
    make_engines(smk.params.cfg, read_dataset(smk.input[0])),
    smk.output[0],
    smk.params.cfg,
    None,
    title="tunnel: ray engines compared at fixed offsets",
)
