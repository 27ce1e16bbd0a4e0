"""Adapter: summary, cost, sensitivity -> results/handover/key_numbers.json."""

from railradio.handover.band import sigma0_and_gaph
from railradio.handover.keys import key_numbers
from railradio.handover.params import scenario_from_config
from railradio.io import read_dataset, write_json
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
scn = scenario_from_config(smk.params.sim)
sigma0, gaph = sigma0_and_gaph(scn.radio, scn.joint)
write_json(
    smk.output[0],
    key_numbers(
        read_dataset(smk.input.summary),
        read_dataset(smk.input.cost),
        read_dataset(smk.input.sensitivity),
        gaph,
        sigma0,
        scn.joint.wslr,
        scn.radio,
    ),
)
