"""Adapter: channel table -> RSSI map, delay spread, strong rays along the tunnel."""

from railradio.io import read_dataset, write_dataset
from railradio.tunnel.study import make_map
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
ds = make_map(smk.params.cfg, read_dataset(smk.input[0]), smk.wildcards.name)
write_dataset(ds, smk.output[0], smk.params.cfg, None, title=f"tunnel: RSSI map ({smk.wildcards.name})")
