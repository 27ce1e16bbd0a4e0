"""Adapter: the reproduction map's key numbers -> results/nr/map/reproduction_map.nc
(railradio.nr.study.map_dataset)."""

import json

from railradio.io import write_dataset
from railradio.nr.study.map_dataset import map_dataset
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
with open(smk.input[0], encoding="utf-8") as fh:
    numbers = json.load(fh)
nr = dict(smk.params.nr)
ds = map_dataset(numbers, dict(smk.params.cells), nr)
write_dataset(
    ds,
    smk.output[0],
    {"map": nr["map"], "cells": dict(smk.params.cells)},
    None,
    "nr reproduction map: the source's claims per map cell and receiver",
)
