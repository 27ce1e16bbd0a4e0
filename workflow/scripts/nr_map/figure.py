"""Adapter: map key numbers -> results/figures/nr_reproduction_map.{pdf,png}."""

import json

from railradio.nr.study.map_figures import plot_reproduction_map
from railradio.nr.study.reproduction_map import cell_receivers, receivers
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
with open(smk.input[0], encoding="utf-8") as fh:
    numbers = json.load(fh)
nr = dict(smk.params.nr)
cells = list(smk.params.cells)
rows = {rx: [c for c in cells if rx in cell_receivers(c, nr)] for rx in receivers(nr)}
plot_reproduction_map(numbers, rows, smk.output.pdf, smk.output.png)
