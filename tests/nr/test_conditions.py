"""The source receiver's conditions: the grid, its departures and the smallest set under
which each claim holds."""

import pytest
import yaml

from railradio.config import ConfigError, load_schema, validate_config
from railradio.config_checks import check_config
from railradio.nr.study import conditions as co
from railradio.nr.study import reproduction_map as rm

from ..conftest import ROOT

SCHEMA = load_schema(ROOT / "workflow/schemas/config.schema.yaml")


@pytest.fixture(scope="module")
def nr():
    return validate_config(yaml.safe_load((ROOT / "config/config.yaml").read_text()), SCHEMA)["nr"]


def test_the_grid_by_departures(nr):
    conds = co.conditions(nr)
    assert len(conds) == 3 * 2 * 2  # window (K, 2 km, 1 km) x gate x data (2)
    assert [c.departures for c in conds] == sorted(c.departures for c in conds)
    first = conds[0]  # the source's literal receiver and EKF under the deployment rule
    assert (first.window_m, first.gated, first.data) == (None, False, "others_random")
    assert first.prefix == "nr.map.mt32_others_random.source"
    last = conds[-1]
    assert (last.window_m, last.gated, last.departures) == (1000.0, True, 2)
    assert last.prefix == "nr.map.win1000_none.source_gated"
    assert last.label() == "window 1 km, gated, data: none"
    # every condition is a map cell and one of its trackers
    cells = rm.cells(nr, SCHEMA["properties"]["nr"])
    for c in conds:
        assert c.cell in cells and c.tracker in rm.cell_receivers(c.cell, nr)


def _numbers(nr, holds):
    """Status keys for every condition and claim: HOLDS where ``holds(condition, claim)``."""
    out = {}
    for c in co.conditions(nr):
        for cname in rm.CLAIMS:
            out[f"{c.prefix}.claim.{cname}"] = {"value": rm.HOLDS if holds(c, cname) else rm.FAILS}
    return out


def test_smallest_set_and_its_keys(nr):
    def holds(c, cname):
        if cname == "ekf_mean":  # with the gate, whatever the window
            return c.gated
        if cname == "toa_p95":  # only with both departures, no data
            return c.departures == 2 and c.data == "none"
        return False

    numbers = _numbers(nr, holds)
    keys = co.key_numbers(numbers, nr)
    assert keys["nr.map.conditions.n"]["value"] == 12
    assert keys["nr.map.conditions.ekf_mean.min_departures"]["value"] == 1
    assert keys["nr.map.conditions.ekf_mean.n_holds"]["value"] == 6
    assert keys["nr.map.conditions.ekf_mean.n_fails"]["value"] == 6
    assert keys["nr.map.conditions.toa_p95.min_departures"]["value"] == 2
    assert keys["nr.map.conditions.aod_p95.min_departures"]["value"] is None
    small = co.smallest(numbers, nr)
    # the gate alone, with the source's K, under both data assumptions
    assert [(c.window_m, c.gated, c.data) for c in small["ekf_mean"]] == [
        (None, True, "others_random"),
        (None, True, "none"),
    ]
    assert [c.prefix for c in small["toa_p95"]] == [
        "nr.map.win2000_none.source_gated",
        "nr.map.win1000_none.source_gated",
    ]
    assert small["aod_p95"] == []
    with pytest.raises(KeyError):
        co.key_numbers({}, nr)


def test_unknown_data_assumption_is_refused(nr):
    bad = {**nr, "map": {**nr["map"], "conditions": {"windows_m": [2000.0], "data": ["nowhere"]}}}
    with pytest.raises(ValueError, match="nr.map.conditions.data"):
        co.conditions(bad)


def test_config_checks_name_the_key():
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    cfg["nr"]["map"]["conditions"]["data"] = ["nowhere"]
    with pytest.raises(ConfigError, match=r"nr\.map\.conditions\.data\[0\]"):
        check_config(validate_config(cfg, SCHEMA), SCHEMA)
    cfg["nr"]["map"]["conditions"]["data"] = ["none"]
    cfg["nr"]["map"]["conditions"]["windows_m"] = [2000.0, 2000.2]
    with pytest.raises(ConfigError, match=r"nr\.map\.conditions\.windows_m"):
        check_config(validate_config(cfg, SCHEMA), SCHEMA)


def test_sanity_rows_are_the_single_cells_source_trackers(nr):
    rows = co.sanity_rows(nr)
    p = f"nr.map.{rm.SINGLE_CELL}.source"
    assert [p for p, _ in rows] == [p, f"{p}_gated", f"{p}.diag.nearest"]
    assert "nearest RRH alone" in rows[0][1] and "no gate" in rows[0][1] and "gated" in rows[1][1]
    # not a condition: the departures and the smallest sets ignore it
    assert all(c.cell != rm.SINGLE_CELL for c in co.conditions(nr))
    off = {**nr, "map": {**nr["map"], "conditions": {**nr["map"]["conditions"], "single_rrh": False}}}
    assert co.sanity_rows(off) == [] and co.partial_rows(off) == set()
    assert co.partial_rows(nr) == {f"{p}.diag.nearest"}  # the measurement claims only
