"""Adapter: chain shards -> rates per (position input, policy)."""

from railradio.chain.summary import summarize
from railradio.io import read_dataset, write_dataset
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
write_dataset(
    summarize([read_dataset(f) for f in smk.input]),
    smk.output[0],
    {},
    None,
    title="chain: handover rates per position input and policy",
)
