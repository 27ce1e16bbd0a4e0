"""Adapter: results/nr/fidelity/s*.nc -> key numbers nr.fidelity.*, nr.detector.* and the figure."""

import numpy as np
import xarray as xr

from railradio.io import read_dataset, write_json
from railradio.nr.engine.simulate import scenario_from_config
from railradio.nr.study.fidelity import comparisons
from railradio.nr.study.fidelity_dataset import from_dataset
from railradio.nr.study.fidelity_detector import NOISE_ONLY_ID, noise_false_alarms
from railradio.nr.study.fidelity_keys import detector_key_numbers, key_numbers
from railradio.nr.study.fidelity_stats import summarize
from railradio.nr.study.figures import plot_fidelity
from railradio.rng import make_rng, spawn_key
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
ds = xr.concat([read_dataset(p) for p in smk.input], dim="epoch").sortby("epoch")
scn = scenario_from_config(dict(smk.params.sim))
comps = comparisons(scn)
stacked, truth = from_dataset(ds)
receivers = [str(r) for r in ds["receiver"].values]
summary = summarize(stacked, truth, receivers, comps, seed=smk.params.seed)
seconds = {str(v): float(np.nanmean(ds["seconds"].sel(path=v).values)) for v in ds["path"].values}
noise = noise_false_alarms(scn, int(smk.params.noise_bursts), make_rng(smk.params.seed, spawn_key("nr", NOISE_ONLY_ID)))
numbers = key_numbers(summary, comps, ds.sizes["epoch"], seconds) | detector_key_numbers(ds, noise)
write_json(smk.output.json, numbers)
plot_fidelity(summary, smk.output.pdf, smk.output.png)
