"""Adapter: results/nr/along/along_track.nc -> figure nr_along_track."""

from railradio.io import read_dataset
from railradio.nr.study.along_track import plot_along
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
plot_along(read_dataset(smk.input[0]), smk.output.pdf, smk.output.png)
