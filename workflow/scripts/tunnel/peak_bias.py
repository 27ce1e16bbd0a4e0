"""Adapter: the engine's table -> results/tunnel/peak_bias.nc (wideband peak-bias decomposition)."""

import numpy as np

from railradio.io import read_dataset, write_dataset
from railradio.rng import spawn_key
from railradio.tunnel.peak_bias import make_peak_bias
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
log = setup_script(smk.log[0])
ds = make_peak_bias(smk.params.cfg, read_dataset(smk.input[0]))
for case, b in zip(ds["case"].values, ds["peak_bias_s"].values, strict=True):
    log.info("%s: median peak bias %.2f ns", case, 1e9 * float(np.median(b)))
write_dataset(
    ds,
    smk.output[0],
    smk.params.cfg,
    spawn_key("tunnel", 600),
    title="tunnel: wideband CIR-peak delay bias by channel case",
)
