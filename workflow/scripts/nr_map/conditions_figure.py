"""Adapter: map key numbers -> results/figures/nr_conditions.{pdf,png} (the source
receiver's conditions, railradio.nr.study.conditions)."""

import json

from railradio.nr.study import conditions
from railradio.nr.study.map_figures import DATA_LABELS, plot_conditions
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
with open(smk.input[0], encoding="utf-8") as fh:
    numbers = json.load(fh)
nr = dict(smk.params.nr)
rows = [(c.prefix, c.label(DATA_LABELS)) for c in conditions.conditions(nr)]
smallest = {k: [c.prefix for c in v] for k, v in conditions.smallest(numbers, nr).items()}
plot_conditions(
    numbers,
    rows,
    smallest,
    smk.output.pdf,
    smk.output.png,
    sanity=conditions.sanity_rows(nr),
    partial=conditions.partial_rows(nr),
)
