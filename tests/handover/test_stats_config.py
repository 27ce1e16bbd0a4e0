"""Binomial intervals against scipy, the clustered rate, the cost grid's noise-free limit,
and the schema rejecting bad handover values."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.stats import binomtest

from railradio.config import ConfigError, load_schema, validate_config
from railradio.handover.cost import cost_grid, full_weight_table, geometric_weight_table
from railradio.handover.params import Scenario
from railradio.stats import clopper_pearson_interval, clustered_rate, wilson_interval

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize(("k", "n"), [(0, 50), (3, 1000), (25, 10000), (500, 1000), (1000, 1000)])
def test_intervals_match_scipy(k, n):
    ref_w = binomtest(k, n).proportion_ci(0.95, method="wilson")
    ref_e = binomtest(k, n).proportion_ci(0.95, method="exact")
    assert wilson_interval(k, n) == pytest.approx((ref_w.low, ref_w.high), abs=1e-12)
    assert clopper_pearson_interval(k, n) == pytest.approx((ref_e.low, ref_e.high), abs=1e-9)


def test_wilson_interval_covers_at_the_nominal_rate(rng):
    p, n = 0.0025, 100_000
    k = rng.binomial(n, p, size=4000)
    lo, hi = wilson_interval(k, n)
    cover = np.mean((lo <= p) & (p <= hi))
    assert 0.935 < cover < 0.965


def test_clustered_rate_reduces_to_binomial_and_inflates_for_correlated_nodes(rng):
    e = rng.random((20000, 1)) < 0.01
    r = clustered_rate(e)
    lo, hi = wilson_interval(e.sum(), e.size)
    assert r["n_eff"] == pytest.approx(e.size, rel=0.05)
    assert (r["lo"], r["hi"]) == pytest.approx((lo, hi), rel=0.05)
    same = np.repeat(rng.random((2500, 1)) < 0.05, 8, axis=1)  # 8 nodes fail together
    rs = clustered_rate(same)
    assert rs["n_eff"] == pytest.approx(2500, rel=0.01)
    assert clustered_rate(np.zeros((100, 8)))["n_eff"] == 100


def test_cost_grid_noise_free_limit_is_one_over_n():
    """Without noise every node converges at once (C = 1) and no correction spreads the
    triggers (F = 0): J = 1/N for every (m, alpha)."""
    base = Scenario()
    scn = replace(
        base,
        radio=replace(base.radio, shadow_sigma_db=0.0, meas_sigma_db=0.0, offset_m=0.01),
        train=replace(base.train, gnss_sigma_m=0.0),
    )
    ds = cost_grid(scn, 300.0, 1, 1, 3, [1, 2, 3], np.array([0.2, 0.7]), 2, 0.5)
    np.testing.assert_allclose(ds["cost"].values, 1 / scn.train.n_nodes)
    assert geometric_weight_table(3, np.array([0.5]))[0].tolist() == [0.5, 0.25, 0.125]
    assert full_weight_table(2, 0.25).shape == (9, 2)


def _config():
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    return cfg, load_schema(ROOT / "workflow/schemas/config.schema.yaml")


@pytest.mark.parametrize(
    ("path", "value"),
    [
        (("joint", "wslr"), "median"),
        (("radio", "load_factor"), 1.5),
        (("sweep", "speeds_kmh"), [100, "fast"]),
        (("a3", "ttt_s"), -0.1),
        (("train", "n_nodes"), 0),
    ],
)
def test_schema_rejects_bad_handover_values(path, value):
    cfg, schema = _config()
    validate_config(cfg, schema)  # the paper-scale config is valid
    cfg, schema = _config()
    cfg["handover"][path[0]][path[1]] = value
    with pytest.raises(ConfigError, match=f"config key 'handover.{path[0]}.{path[1]}"):
        validate_config(cfg, schema)


def test_pingpong_claim_is_strict_and_can_fail():
    import xarray as xr

    from railradio.handover.keys import pingpong_strictly_lowest

    # speeds: A3 and distance clearly above joint; distance zero (a tie); overlapping intervals
    hi = np.array([[0.001, 0.001, 0.001], [0.05, 0.05, 0.05], [0.03, 0.0005, 0.004]])
    lo = np.array([[0.0, 0.0, 0.0], [0.04, 0.04, 0.04], [0.02, 0.0, 0.0005]])
    ds = xr.Dataset(
        {"pingpong_hi": (("policy", "speed_kmh"), hi), "pingpong_lo": (("policy", "speed_kmh"), lo)},
        coords={"policy": ["joint", "a3", "distance"], "speed_kmh": [100.0, 250.0, 350.0]},
    )
    np.testing.assert_array_equal(pingpong_strictly_lowest(ds), [True, False, False])


def test_sensitivity_case_values_print_as_configured():
    import xarray as xr

    from railradio.handover.keys import sens_values
    from railradio.keynumbers import format_number

    ds = xr.Dataset(
        {
            "switch": ("case", ["none", "a3.ttt_s", "radio.load_factor", "joint.wslr"]),
            "value": ("case", ["reference", "0.64", "0.3", "mean"]),
        },
        coords={"case": ["reference", "ttt_s_0p64", "load_factor_0p3", "wslr_mean"]},
    )
    out = sens_values(ds)
    assert set(out) == {"handover.sens.ttt_s_0p64.value", "handover.sens.load_factor_0p3.value"}
    e = out["handover.sens.ttt_s_0p64.value"]
    assert e["unit"] == "s" and format_number(e["value"], e["digits"]) == "0.64"
    assert (
        format_number(
            out["handover.sens.load_factor_0p3.value"]["value"], out["handover.sens.load_factor_0p3.value"]["digits"]
        )
        == "0.3"
    )
