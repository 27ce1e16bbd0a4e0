"""Tests of the chain study: nr tracked position error -> handover position input."""

from dataclasses import replace

import numpy as np
import pytest
import xarray as xr
import yaml

from railradio.chain.nr_error import bootstrap, error_stats, hold_and_drift, nofix_share, series_from_runs
from railradio.chain.params import ChainParams, params_from_config
from railradio.chain.sim import gm_error_m, simulate_block, simulate_blocks
from railradio.chain.summary import crossover, key_numbers, summarize
from railradio.config import ConfigError, load_schema, validate_config
from railradio.handover.engine import simulate_block as ho_simulate_block
from railradio.handover.params import Scenario
from tests.conftest import ROOT

SPEED = 350.0


def _scn(sigma_m: float = 0.0) -> Scenario:
    base = Scenario()
    return replace(base, train=replace(base.train, gnss_sigma_m=sigma_m)).with_weights(2, 0.5)


def _nr_dataset(err: np.ndarray, v_m_s: np.ndarray, dt: float = 0.1) -> xr.Dataset:
    """A stand-in nr IMM file: along_err for ekf and imm, speed profile v_m_s."""
    t = dt * np.arange(err.size)
    x = np.concatenate([[0.0], np.cumsum(v_m_s[:-1] * dt)])
    return xr.Dataset(
        {"along_err": (("filter", "epoch"), np.stack([err, 2 * err])), "t": ("epoch", t), "x_true": ("epoch", x)},
        coords={"filter": ["ekf", "imm"], "epoch": np.arange(err.size)},
    )


def _series(rng, n=3000, drift=0.5):
    e = np.cumsum(rng.standard_normal(n)) * 0.01 + rng.exponential(0.3, n)  # skewed, correlated
    ds = _nr_dataset(e, np.full(n, SPEED / 3.6))
    return series_from_runs([ds], "ekf", SPEED, 50.0, drift), e


# --- sigma = 0 is the handover study's own run with a zero GNSS error -------------------


def test_sigma0_chain_equals_handover_with_zero_gnss_error():
    chained = simulate_block(_scn(2.0), SPEED, 7, 3, 12, [0.0], 1.0, {})["gm_0"]
    ref = ho_simulate_block(_scn(0.0), SPEED, 7, 3, 12, ("joint", "distance", "a3"))
    for p in ("joint", "distance", "a3"):
        for name in ("success", "pingpong", "delay_s"):
            np.testing.assert_array_equal(chained[p][name], np.asarray(ref[p][name][1], dtype=float))


def test_gm_input_equals_handover_engine_with_an_unreachable_bound():
    """At sigma = 2 m the chain's untruncated error differs from the handover's only where the
    handover clips at 5 m: with an unreachable bound the handover run equals the chain's."""
    base = _scn(2.0)
    wide = replace(base, train=replace(base.train, gnss_bound_m=1000.0))
    chained = simulate_block(base, SPEED, 7, 1, 10, [2.0], 1.0, {})["gm_2"]
    ref = ho_simulate_block(wide, SPEED, 7, 1, 10, ("joint", "distance"))
    for p in ("joint", "distance"):
        np.testing.assert_array_equal(chained[p]["success"], np.asarray(ref[p]["success"][1], dtype=float))


def test_a3_ignores_position_and_shards_do_not_matter(rng):
    s, _ = _series(rng)
    whole = simulate_blocks(_scn(), SPEED, 5, range(0, 2), 6, [0.0, 50.0], 1.0, {"ekf": s})
    parts = [simulate_blocks(_scn(), SPEED, 5, range(b, b + 1), 6, [0.0, 50.0], 1.0, {"ekf": s}) for b in (0, 1)]
    xr.testing.assert_equal(whole, xr.concat(parts, dim="run", data_vars="minimal", coords="minimal"))
    a3 = whole["success"].sel(policy="a3").values
    assert np.all(a3 == a3[0])  # identical for every position input
    # a 50 m error changes the joint decision's commands somewhere
    assert np.any(
        whole["delay_s"].sel(policy="joint", input="gm_0").values
        != whole["delay_s"].sel(policy="joint", input="gm_50").values
    )


# --- the Gauss-Markov input -------------------------------------------------------------


def test_gm_error_is_untruncated_with_the_stated_std_and_correlation(rng):
    w = rng.standard_normal((4000, 200))
    e = gm_error_m(w, 20.0, 1.0, 0.04)
    assert np.std(e) == pytest.approx(20.0, rel=0.02)
    assert np.max(np.abs(e)) > 60.0  # no clipping at the handover's 5 m bound (nor near 3 sigma)
    rho = np.mean(e[:, 1:] * e[:, :-1]) / np.mean(e * e)
    assert rho == pytest.approx(np.exp(-0.04), abs=0.005)
    assert np.all(gm_error_m(w, 0.0, 1.0, 0.04) == 0)


# --- the nr bootstrap --------------------------------------------------------------------


def test_bootstrap_reproduces_the_input_error_distribution(rng):
    s, e = _series(rng)
    boot = bootstrap(s, 4000, 60, 0.04, np.random.default_rng(1))
    for q in (5, 25, 50, 75, 95):
        assert np.percentile(boot, q) == pytest.approx(np.percentile(e, q), abs=0.02)
    assert boot.mean() == pytest.approx(e.mean(), abs=0.01)
    # zero-order hold at 40 ms of a 100 ms series: consecutive samples mostly repeat the epoch
    same = np.mean(boot[:, 1:] == boot[:, :-1])
    assert same == pytest.approx(1 - 0.4, abs=0.03)
    # the within-crossing time correlation is the series' own (lag 100 ms = 2.5 samples at 40 ms)
    lag_src = np.corrcoef(e[5:], e[:-5])[0, 1]
    lag_boot = np.corrcoef(boot[:, 25:-5].ravel(), boot[:, 12:-18].ravel())[0, 1]  # 13 samples = 0.52 s ~ 5 epochs
    assert lag_boot == pytest.approx(lag_src, abs=0.05)


def test_bootstrap_is_reproducible_and_wraps_within_segments(rng):
    # two segments at the chain speed separated by slow epochs
    e = np.arange(300, dtype=float)
    v = np.full(300, SPEED / 3.6)
    v[100:150] = 10.0
    s = series_from_runs([_nr_dataset(e, v)], "ekf", SPEED, 50.0, 0.0)
    assert len(s.lengths) == 2  # two segments at the chain speed
    a = bootstrap(s, 50, 400, 0.04, np.random.default_rng(3))
    b = bootstrap(s, 50, 400, 0.04, np.random.default_rng(3))
    np.testing.assert_array_equal(a, b)
    for row in a:  # every crossing stays in one segment (values of one segment only)
        assert np.all(row < 100) or np.all(row >= 150)


def test_outages_hold_the_last_fix_and_drift():
    e = np.array([1.0, np.nan, np.nan, 2.0, np.nan])
    f, age = hold_and_drift(e, 0.1, 0.5)
    np.testing.assert_allclose(f, [1.0, 1.05, 1.1, 2.0, 2.05])
    np.testing.assert_allclose(age, [0, 0.1, 0.2, 0, 0.1])
    ds = _nr_dataset(np.array([np.nan, 0.0, np.nan, np.nan, 1.0, 1.0]), np.full(6, SPEED / 3.6))
    s = series_from_runs([ds], "ekf", SPEED, 50.0, 2.0)
    assert s.outage_share == pytest.approx(3 / 6)
    boot = bootstrap(s, 400, 5, 0.1, np.random.default_rng(0))
    vals = set(np.round(boot.ravel(), 9))
    assert vals <= {0.0, 0.2, -0.2, 0.4, -0.4, 1.0}  # hold 0 then +-2 m/s x age
    assert {0.4, -0.4} <= vals  # both drift signs occur


def test_nofix_share_counts_epochs_without_any_detection():
    n = 4
    aod = np.zeros((2, n, 2))
    aod[1, 1:3] = np.nan
    rng_err = aod.copy()
    rng_err[1, 2, 0] = 0.0  # epoch 2 has a TOA: not an outage
    ds = xr.Dataset(
        {
            "aod_err": (("receiver", "epoch", "slot"), aod),
            "range_err": (("receiver", "epoch", "slot"), rng_err),
            "t": ("epoch", 0.1 * np.arange(n)),
            "x_true": ("epoch", SPEED / 3.6 * 0.1 * np.arange(n)),
        },
        coords={"receiver": ["source", "robust"]},
    )
    assert nofix_share([ds], "robust", SPEED, 50.0) == pytest.approx(1 / 4)
    with pytest.raises(ValueError, match="receiver"):
        nofix_share([ds], "other", SPEED, 50.0)


# --- crossover ---------------------------------------------------------------------------


def test_crossover_interpolates_the_first_crossing():
    assert crossover([0, 10, 20], [0.9, 0.7, 0.5], 0.6) == (pytest.approx(15.0), "found")
    # the first downward crossing, not a later one; exact grid hit
    assert crossover([0, 1, 2, 3], [0.9, 0.6, 0.8, 0.1], 0.6) == (pytest.approx(1.0), "found")
    s, st = crossover([0, 10], [0.9, 0.8], 0.6)
    assert np.isnan(s) and st == "above"
    s, st = crossover([0, 10], [0.5, 0.8], 0.6)
    assert np.isnan(s) and st == "never"


def test_key_numbers_report_the_crossover_and_nr_points():
    sig = np.array([0.0, 10.0, 100.0, np.nan])
    labels = ["gm_0", "gm_10", "gm_100", "nr_ekf"]
    succ = np.array([[0.9, 0.95, 0.6], [0.85, 0.94, 0.6], [0.5, 0.3, 0.6], [0.9, 0.95, 0.6]])
    d = {
        n: (("input", "policy"), succ + off)
        for n, off in (("success", 0), ("success_lo", -0.01), ("success_hi", 0.01), ("success_se", 0.0 * succ + 0.005))
    }
    d.update(
        {n: (("input", "policy"), np.zeros((4, 3))) for n in ("pingpong", "pingpong_lo", "pingpong_hi", "pingpong_se")}
    )
    d["err_rms_m"] = (("input",), np.array([0, 10, 100, 0.2]))
    summ = xr.Dataset(d, coords={"input": labels, "sigma_m": ("input", sig), "policy": ["joint", "distance", "a3"]})
    summ["speed_kmh"] = 350.0
    summ["n_handovers"] = 800.0
    st = {"mean": 0.0, "std": 0.1, "rms": 0.1, "p95": 0.2, "outage_share": 0.0, "nofix_share": 0.0, "epochs": 10.0}
    k = key_numbers(summ, {"ekf": st}, 20.0)
    # joint: 0.85 -> 0.5 between 10 and 100 m crosses 0.6 at 10 + 90 * 0.25/0.35
    assert k["chain.sigma_crossover_m"]["value"] == pytest.approx(10 + 90 * 0.25 / 0.35)
    assert k["chain.sigma_crossover_status"]["value"] == 0
    assert k["chain.nr_ekf.joint.success.v350"]["value"] == pytest.approx(0.9)
    assert k["chain.joint.beats_a3_all_sigma_fig"]["value"] == 1.0


# --- bad input ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kw", "name"),
    [
        ({"sigmas_m": (0.0, -1.0)}, "sigmas_m"),
        ({"sigmas_m": (0.0, 5.0, 2.0)}, "sigmas_m"),
        ({"nr_filters": ("rts",)}, "nr_filters"),
        ({"speed_kmh": 0.0}, "speed_kmh"),
        ({"outage_drift_m_s": -1.0}, "outage_drift_m_s"),
        ({"n_blocks": 0}, "n_blocks"),
    ],
)
def test_bad_parameters_raise_naming_the_parameter(kw, name):
    with pytest.raises(ValueError, match=name):
        ChainParams(**kw)


def test_bad_inputs_raise(rng):
    s, _ = _series(rng)
    with pytest.raises(ValueError, match="n_runs"):
        bootstrap(s, 0, 10, 0.04, rng)
    with pytest.raises(ValueError, match="sample_period_s"):
        bootstrap(s, 1, 10, 0.0, rng)
    ds = _nr_dataset(np.zeros(20), np.full(20, 10.0))
    with pytest.raises(ValueError, match="speed_kmh"):
        series_from_runs([ds], "ekf", SPEED, 50.0, 0.5)
    with pytest.raises(ValueError, match="filt"):
        series_from_runs([ds], "rts", SPEED, 50.0, 0.5)
    with pytest.raises(ValueError, match="sigma_m"):
        gm_error_m(np.zeros((2, 3)), -1.0, 1.0, 0.04)
    with pytest.raises(ValueError, match="unknown chain parameter"):
        params_from_config({"speed": 3})
    with pytest.raises(ValueError):
        crossover([0, 0], [0.5, 0.4], 0.3)
    with pytest.raises(ValueError, match="err_m"):
        error_stats(np.array([np.nan]))


@pytest.mark.parametrize(
    ("key", "value"),
    [("sigmas_m", [0.0, -2.0]), ("nr_filters", ["rts"]), ("n_blocks", 0), ("speed_halfwidth_kmh", 0.0)],
)
def test_schema_rejects_bad_chain_values(key, value):
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    schema = load_schema(ROOT / "workflow/schemas/config.schema.yaml")
    validate_config(cfg, schema)
    cfg["chain"][key] = value
    with pytest.raises(ConfigError, match=f"config key 'chain.{key}"):
        validate_config(cfg, schema)


def test_summary_rates_match_the_raw_outcomes(rng):
    s, _ = _series(rng)
    ds = simulate_blocks(_scn(), SPEED, 5, range(0, 1), 8, [0.0, 5.0], 1.0, {"ekf": s})
    summ = summarize([ds])
    for lab in ("gm_0", "nr_ekf"):
        for p in ("joint", "a3"):
            assert float(summ["success"].sel(input=lab, policy=p)) == pytest.approx(
                float(ds["success"].sel(input=lab, policy=p).mean())
            )
    assert float(summ["err_rms_m"].sel(input="gm_0")) == 0.0
