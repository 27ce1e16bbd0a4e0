"""Adapter: sensitivity key numbers -> results/figures/nr_sweeps.{pdf,png}."""

import json

from railradio.nr.study.figures import plot_sweeps
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
with open(smk.input.numbers, encoding="utf-8") as fh:
    numbers = json.load(fh)
plot_sweeps(numbers, dict(smk.params.sweeps), dict(smk.params.sync_sigma_s), smk.output.pdf, smk.output.png)
