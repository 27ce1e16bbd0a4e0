"""Adapter: results/nr/imm/{real}.nc -> results/nr/imm/key_numbers.json."""

from railradio.io import read_dataset, write_json
from railradio.nr.study.imm_report import key_numbers
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
write_json(smk.output[0], key_numbers([read_dataset(p) for p in smk.input], smk.params.window_s))
