"""Adapter: ray families -> tabulated slot-to-receiver channel results/tunnel/table_{name}.nc."""

from railradio.io import read_dataset, write_dataset
from railradio.tunnel.study import make_table
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
log = setup_script(smk.log[0])
cfg = smk.params.cfg
ds = make_table(cfg, smk.wildcards.name, smk.params.seed, read_dataset(smk.input[0]))
log.info("table %s: order %s, %s families", smk.wildcards.name, ds.attrs["reflection_order"], ds.attrs["n_families"])
write_dataset(
    ds,
    smk.output[0],
    cfg,
    None if smk.wildcards.name != "source" else (3, 10),
    title=f"tunnel: slot-to-receiver channel by along-axis offset ({smk.wildcards.name})",
)
