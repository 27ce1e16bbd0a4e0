"""Adapter: the two sensitivity sweeps -> results/sens/fusion/key_numbers.json (sens.fusion.*)."""

from railradio.fusion.sensitivity_keys import key_numbers
from railradio.io import read_dataset, write_json
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
write_json(smk.output[0], key_numbers(read_dataset(smk.input.curve), read_dataset(smk.input.rho)))
