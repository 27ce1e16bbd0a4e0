"""Adapter: nr intermediates -> all nr figures."""

from railradio.io import read_dataset
from railradio.nr.study import figures as f
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
out = {p.rsplit("/", 1)[1].rsplit(".", 1)[0]: p for p in smk.output if p.endswith(".pdf")}
png = {k: v[:-4] + ".png" for k, v in out.items()}
tracks = [read_dataset(p) for p in smk.input.tracks]
bounds = [read_dataset(p) for p in smk.input.bounds]
f.plot_trajectory(read_dataset(smk.input.trajectory), out["nr_trajectory"], png["nr_trajectory"])
f.plot_burst_correlation(read_dataset(smk.input.samples), out["nr_burst_correlation"], png["nr_burst_correlation"])
f.plot_measurement_cdf(tracks, out["nr_measurement_error_cdf"], png["nr_measurement_error_cdf"])
f.plot_position_cdf(tracks, out["nr_position_error_cdf"], png["nr_position_error_cdf"], bounds=bounds)
f.plot_error_vs_time(tracks[0], out["nr_position_error_vs_time"], png["nr_position_error_vs_time"], bounds=bounds[0])
