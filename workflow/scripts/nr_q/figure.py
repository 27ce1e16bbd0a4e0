"""Adapter: results/nr/q_band/q_band.nc -> figure nr_q_band."""

from railradio.io import read_dataset
from railradio.nr.study.q_band import plot_band
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
plot_band(read_dataset(smk.input[0]), smk.output.pdf, smk.output.png)
