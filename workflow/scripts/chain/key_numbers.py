"""Adapter: chain summary + nr files -> results/chain/key_numbers.json."""

from railradio.chain.nr_error import nofix_share, nr_statistics, series_from_runs
from railradio.chain.params import params_from_config
from railradio.chain.summary import key_numbers
from railradio.io import read_dataset, write_json
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
p = smk.params
ch = params_from_config(dict(p.chain))
runs = [read_dataset(f) for f in smk.input.nr]
nofix = nofix_share([read_dataset(f) for f in smk.input.track], p.receiver, ch.speed_kmh, ch.speed_halfwidth_kmh)
stats = {
    f: nr_statistics(series_from_runs(runs, f, ch.speed_kmh, ch.speed_halfwidth_kmh, ch.outage_drift_m_s), nofix)
    for f in ch.nr_filters
}
write_json(smk.output[0], key_numbers(read_dataset(smk.input.summary), stats, p.figure_max_sigma_m))
