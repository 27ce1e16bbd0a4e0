"""Shared adapter code of the nr scripts: config -> scenario, reading shards."""

import xarray as xr

from railradio.io import read_dataset
from railradio.nr.simulate import scenario_from_config


def scenario(smk):
    return scenario_from_config(dict(smk.params.sim))


def read_shards(paths):
    # per-epoch variables are concatenated; the others (the train's geometry) are the same
    # in every shard
    return xr.concat(
        [read_dataset(p) for p in paths], dim="epoch", data_vars="minimal", coords="minimal", compat="override"
    )
