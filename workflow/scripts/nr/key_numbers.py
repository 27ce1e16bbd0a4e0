"""Adapter: track datasets and the calibration -> results/nr/key_numbers.json."""

import json

from railradio.io import read_dataset, write_json
from railradio.nr.study.keys import calibration_key_numbers, key_numbers
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
cal = json.loads(open(smk.input.calibration, encoding="utf-8").read())
write_json(
    smk.output[0],
    key_numbers([read_dataset(p) for p in smk.input.tracks], [read_dataset(p) for p in smk.input.bounds])
    | calibration_key_numbers(cal),
)
