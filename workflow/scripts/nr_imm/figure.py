"""Adapter: results/nr/imm/{real}.nc -> figure nr_imm_lag."""

from railradio.io import read_dataset
from railradio.nr.study.imm_report import plot_lag
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
plot_lag([read_dataset(p) for p in smk.input], smk.output.pdf, smk.output.png, smk.params.window_s)
