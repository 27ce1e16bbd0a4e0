"""Adapter: every map cell's tracks -> results/nr/map/key_numbers.json (with the source
receiver's conditions, railradio.nr.study.conditions)."""

import json

from railradio.io import read_dataset, write_json
from railradio.nr.study import conditions
from railradio.nr.study.block_bootstrap import block_indices
from railradio.nr.study.keys import SKIP_S
from railradio.nr.study.map_diagnostics import (
    ENDFIRE_EDGES_DEG,
    along_cross_key_numbers,
    calibration_diag_key_numbers,
    diagnostic_key_numbers,
    endfire_bias_key_numbers,
    nearest_key_numbers,
    off_air_key_numbers,
)
from railradio.nr.study.reproduction_map import cell_key_numbers, summary_key_numbers
from railradio.nr.tracking import loss
from railradio.rng import make_rng, spawn_key
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
mp, nr = dict(smk.params.map), dict(smk.params.nr)
first, end = mp["segment"]
numbers = {}
for cell, path in zip(smk.params.cells, smk.input, strict=True):
    ds = read_dataset(path)
    ds = ds.isel(epoch=ds["t"].values >= ds["t"].values[0] + SKIP_S)  # the trackers' start skipped
    spacing = loss.rrh_spacing_m(ds)
    # the resamples cell_key_numbers draws from the same key (paired across the map)
    idx = block_indices(
        make_rng(int(smk.params.seed), spawn_key("nr", 2000)),
        ds.sizes["epoch"],
        int(mp["block_epochs"]),
        int(mp["n_boot"]),
    )
    for rx in [str(r) for r in ds["receiver"].values]:
        d = ds.sel(receiver=rx)
        where = (
            f"{rx} receiver{', gated' if bool(d['gated']) else ''}, map cell {cell}, epochs "
            f"{int(ds['epoch'][0])}..{end - 1} of r0"
        )
        # the same resamples for every cell and receiver: paired comparisons across the map
        numbers |= cell_key_numbers(
            cell,
            rx,
            d["aod_err"].values,
            d["range_err"].values,
            {str(v): d["pos_err"].sel(measurements=v).values for v in d["measurements"].values},
            spacing,
            make_rng(int(smk.params.seed), spawn_key("nr", 2000)),
            int(mp["block_epochs"]),
            int(mp["n_boot"]),
            float(mp["confidence"]),
            where,
        )
        numbers |= diagnostic_key_numbers(
            cell, rx, d["aod_err"].values, d["aod_true"].values, d["n_detected"].values, where
        )
        numbers |= endfire_bias_key_numbers(
            cell, rx, d["aod_err"].values, d["aod_true"].values, ENDFIRE_EDGES_DEG, where
        )
        fused = d["pos_err"].sel(measurements="aod_toa").values
        along = d["along_err"].sel(measurements="aod_toa").values
        numbers |= along_cross_key_numbers(cell, rx, along, fused, spacing, where)
        numbers |= nearest_key_numbers(
            cell, rx, d["nearest_aod_err"].values, d["nearest_range_err"].values, idx, float(mp["confidence"]), where
        )
        numbers |= off_air_key_numbers(
            cell,
            rx,
            d["aod_err"].notnull().values,
            d["selected_off_air"].values.astype(bool),
            d["selected_off_air_pss"].values.astype(bool),
            d["selected_off_air_locked"].values.astype(bool),
            where,
        )
        numbers |= calibration_diag_key_numbers(cell, rx, json.loads(ds.attrs["config_json"])["calibration"], where)
numbers |= summary_key_numbers(numbers, list(smk.params.cells), nr)
write_json(smk.output[0], numbers | conditions.key_numbers(numbers, nr))
