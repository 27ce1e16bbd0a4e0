"""Adapter: the two sensitivity sweeps -> figure fusion_sensitivity (PDF + PNG)."""

from railradio.fusion.sensitivity_figures import plot_sensitivity
from railradio.io import read_dataset
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
plot_sensitivity(read_dataset(smk.input.curve), read_dataset(smk.input.rho), smk.output.pdf, smk.output.png)
