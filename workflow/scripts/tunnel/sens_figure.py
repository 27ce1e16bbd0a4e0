"""Adapter: sensitivity datasets -> results/figures/tunnel_sensitivity.{pdf,png}."""

from railradio.io import read_dataset
from railradio.tunnel.figures import sensitivity
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
sv = smk.params.sensitivity
sens = {t: read_dataset(p) for t, p in zip(smk.params.trains, smk.input, strict=True)}
sensitivity(sens, sv["shadow_sigma_db"], sv["delay_sigma_ns"], sv["delay_errors"], smk.output.pdf, smk.output.png)
