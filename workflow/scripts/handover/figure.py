"""Adapter: one handover figure (PDF + PNG)."""

from railradio.handover.figures import FIGURES
from railradio.io import read_dataset
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
_, plot = FIGURES[smk.wildcards.name]
plot(read_dataset(smk.input[0]), smk.output.pdf, smk.output.png)
