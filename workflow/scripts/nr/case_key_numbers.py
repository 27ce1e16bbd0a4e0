"""Adapter: sensitivity-case tracks + the main r0 track -> results/nr/cases/key_numbers.json."""

from railradio.io import read_dataset, write_json
from railradio.nr.study.keys import sensitivity_floor_numbers, sensitivity_key_numbers
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
cases = {c: read_dataset(p) for c, p in zip(smk.params.cases, smk.input.cases, strict=True)}
numbers = sensitivity_key_numbers(read_dataset(smk.input.base), cases, dict(smk.params.n_epochs))
write_json(smk.output[0], numbers | sensitivity_floor_numbers(dict(smk.params.sync_sigma_s)))
