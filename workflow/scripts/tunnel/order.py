"""Adapter: reflection order by convergence -> results/tunnel/order_{placement}.nc."""

from railradio.io import write_dataset
from railradio.tunnel.study import make_order
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
log = setup_script(smk.log[0])
ds = make_order(smk.params.cfg)
log.info("placement %s: order %s", smk.wildcards.placement, ds.attrs["reflection_order"])
write_dataset(
    ds,
    smk.output[0],
    smk.params.cfg,
    None,
    title=f"tunnel: reflection order by convergence of the coherent gain ({smk.wildcards.placement})",
)
