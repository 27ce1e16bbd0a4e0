"""Adapter: one fusion sweep -> its RMSE figure (PDF + PNG)."""

from railradio.fusion.figures import plot_sweep
from railradio.fusion.montecarlo import SWEEP_PARAMETER
from railradio.io import read_dataset
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
plot_sweep(read_dataset(smk.input[0]), SWEEP_PARAMETER[smk.params.sweep], smk.output.pdf, smk.output.png)
