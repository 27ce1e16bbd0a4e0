"""Adapter: chain summary -> chain_success_vs_sigma (PDF + PNG)."""

from railradio.chain.figures import plot_success_vs_sigma
from railradio.io import read_dataset
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
plot_success_vs_sigma(read_dataset(smk.input[0]), smk.output.pdf, smk.output.png, smk.params.figure_max_sigma_m)
