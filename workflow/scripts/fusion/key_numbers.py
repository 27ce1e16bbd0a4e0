"""Adapter: reference point + sweeps -> results/fusion/key_numbers.json."""

from railradio.fusion.keys import key_numbers
from railradio.io import read_dataset, write_json
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
sweeps = {name: read_dataset(p) for name, p in zip(smk.params.sweeps, smk.input.sweeps, strict=True)}
write_json(smk.output[0], key_numbers(read_dataset(smk.input.reference), sweeps))
