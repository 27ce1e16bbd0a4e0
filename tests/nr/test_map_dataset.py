"""The reproduction map as a dataset: every status, value and interval of the map's key
numbers at its (cell, receiver, claim), NaN where a receiver does not run, readable labels."""

import json

import numpy as np
import pytest
import xarray as xr

from railradio.config_checks import check_config
from railradio.nr.study import map_diagnostics as md
from railradio.nr.study import reproduction_map as rm
from railradio.nr.study.map_dataset import map_dataset
from railradio.nr.study.map_figures import cell_label
from railradio.rng import make_rng

from .test_reproduction_map import SCHEMA, _errors, _paper


@pytest.fixture(scope="module")
def paper_cells():
    cfg = _paper()
    return cfg["nr"], check_config(cfg, SCHEMA).nr_map_cells


def _numbers(nr, cells, seed=5):
    rng = np.random.default_rng(seed)
    nums = {}
    for c in cells:
        for rx in rm.cell_receivers(c, nr):
            nums |= rm.cell_key_numbers(c, rx, *_errors(200, rng), 500.0, make_rng(1, (0,)), 50, 50, 0.95, "t")
            nums |= md.diagnostic_key_numbers(c, rx, *_errors(200, rng)[:1], np.zeros((200, 3)), np.ones((200, 3)), "t")
    return nums


def test_every_key_lands_at_its_cell_receiver_and_claim(paper_cells):
    nr, cells = paper_cells
    names = ["mt32_others_random", "mt8_none", "tpl_sss_sel_peak"]
    sub = {c: cells[c] for c in names}
    nums = _numbers(nr, sub)
    ds = map_dataset(nums, sub, nr)
    assert list(ds.cell.values) == names and list(ds.claim.values) == list(rm.CLAIMS)
    assert ds.status.dims == ("cell", "receiver", "claim")
    for c in names:
        for rx in ds.receiver.values:
            for cl, claim in rm.CLAIMS.items():
                got = ds.sel(cell=c, receiver=rx, claim=cl)
                if rx not in rm.cell_receivers(c, nr):  # ours in a template/selection cell
                    assert np.isnan(got.status) and np.isnan(got.value)
                    continue
                p = f"nr.map.{c}.{rx}"
                assert float(got.status) == nums[f"{p}.claim.{cl}"]["value"]
                for v, suffix in (("value", ""), ("lo", ".lo"), ("hi", ".hi")):
                    want = nums[f"{p}.{claim.metric}{suffix}"]["value"]
                    assert float(got[v]) == pytest.approx(np.nan if want is None else want, nan_ok=True)
    assert [str(v) for v in ds.label.values] == [cell_label(c) for c in names]
    assert ds.data_beam.sel(cell="mt8_none").item() == "none" and ds.rrh_elements.sel(cell="mt8_none") == 8
    assert ds.selection.sel(cell="tpl_sss_sel_peak").item() == "peak"
    assert bool(ds.is_default.sel(cell="mt32_others_random")) and not bool(ds.is_default.sel(cell="mt8_none"))
    assert set(np.unique(ds.status.values[np.isfinite(ds.status.values)])) <= {-1.0, 0.0, 1.0}
    assert list(ds.status.attrs["flag_values"]) == [-1.0, 0.0, 1.0]


def test_a_missing_status_is_an_error_not_a_hole(paper_cells):
    nr, cells = paper_cells
    sub = {"mt32_others_random": cells["mt32_others_random"]}
    nums = _numbers(nr, sub)
    del nums["nr.map.mt32_others_random.source.claim.ekf_mean"]
    with pytest.raises(ValueError, match="claim.ekf_mean"):
        map_dataset(nums, sub, nr)
    with pytest.raises(ValueError, match="cells"):
        map_dataset(nums, {}, nr)


def test_the_published_map_as_a_dataset(paper_cells):
    """The paper-scale record (paper/map_numbers.json) fills every cell the map runs."""
    from ..conftest import ROOT

    nr, cells = paper_cells
    ds = map_dataset(json.loads((ROOT / "paper/map_numbers.json").read_text(encoding="utf-8")), cells, nr)
    runs = np.array([[rx in rm.cell_receivers(c, nr) for rx in ds.receiver.values] for c in ds.cell.values])
    assert np.isfinite(ds.status.values[runs]).all() and np.isnan(ds.status.values[~runs]).all()
    assert len(set(ds.label.values)) == ds.sizes["cell"]  # a label names one cell
    # the sanity row: its range and the receiver's own measurements of the one RRH in range
    single = ds.sel(cell=rm.SINGLE_CELL)
    assert float(single.range_m) == pytest.approx(np.hypot(250.0, 15.0)) and float(ds.range_m.max()) == 5000.0
    assert np.isnan(single.search_range_m) and float(ds.search_range_m.sel(cell="win1000_none")) == 1000.0
    assert 0 < float(single.nearest_aod_err_p95_deg.sel(receiver="source")) < 180
    assert float(single.nearest_measured_frac.sel(receiver="robust")) > 0.5
    assert (
        float(single.off_air_frac.sel(receiver="source"))
        > 0
        == float(ds.off_air_frac.sel(cell="mt32_none", receiver="source"))
    )


@pytest.mark.slow
def test_the_ci_run_writes_the_map_dataset(ci_run):
    with xr.open_dataset(ci_run / "results/nr/map/reproduction_map.nc") as ds:
        numbers = json.loads((ci_run / "results/key_numbers.json").read_text(encoding="utf-8"))
        assert ds.sizes["claim"] == len(rm.CLAIMS) and ds.status.attrs["units"] == "1"
        for c in ds.cell.values:
            for rx in ds.receiver.values:
                key = f"nr.map.{c}.{rx}.claim.ekf_mean"
                if key in numbers:
                    assert float(ds.status.sel(cell=c, receiver=rx, claim="ekf_mean")) == numbers[key]["value"]
        assert "config_json" in ds.attrs and ds.attrs["Conventions"].startswith("CF")
