"""Separate head/tail train panels (docs/model/nr.md §1): per-panel paths in the link
budget and the synthesized bursts, and the lever arm in the tracker's measurement model."""

import numpy as np
import pytest
import xarray as xr
import yaml

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.channel.antenna import RrhArray, TrainArray, facing_panel
from railradio.nr.channel.geometry import Deployment
from railradio.nr.channel.link import RadioParams, ShadowingMap, link_budget
from railradio.nr.engine.epochs import simulate_epochs
from railradio.nr.engine.simulate import scenario_from_config
from railradio.nr.tracking.ekf import TrackerConfig
from railradio.nr.tracking.track import track_setup
from railradio.rng import spawn_key

PANELS = (100.0, -100.0)  # an 8-car set, ~200 m


def test_panel_positions_are_validated():
    with pytest.raises(ValueError, match="panel_x_m"):
        TrainArray(panel_x_m=(-1.0, 0.0))
    with pytest.raises(ValueError, match="panel_x_m"):
        TrainArray(panel_x_m=(10.0, 5.0))
    assert TrainArray().co_located and not TrainArray(panel_x_m=PANELS).co_located


def test_co_located_gain_is_the_sum_of_the_two_panels():
    tr = TrainArray()
    aoa = np.radians([5.0, 60.0, 90.0, 150.0])
    want = 10 * np.log10(10 ** (tr.panel_gain_db(aoa, 0) / 10) + 10 ** (tr.panel_gain_db(aoa, 1) / 10))
    np.testing.assert_allclose(tr.gain_db(aoa), want)


def test_link_budget_has_one_path_per_rrh_and_panel():
    dep, radio = Deployment(), RadioParams()
    shadow = ShadowingMap(1, (0,), dep, radio)
    x = 10_250.0
    lb = link_budget(x, 100.0, dep, radio, RrhArray(), TrainArray(panel_x_m=PANELS), shadow, shadowing=False)
    n = lb.rrh.size
    assert lb.links.n == 2 * n and lb.panel.shape == (n,)
    # link delays are the 3-D distances from each panel (RRH-major: head, tail)
    d_head = dep.distance_3d_m(x + PANELS[0], lb.rrh)
    d_tail = dep.distance_3d_m(x + PANELS[1], lb.rrh)
    np.testing.assert_allclose(lb.links.tau_s[0::2] * SPEED_OF_LIGHT_M_S, d_head)
    np.testing.assert_allclose(lb.links.tau_s[1::2] * SPEED_OF_LIGHT_M_S, d_tail)
    # the per-RRH truth is the stronger panel's; RRHs well ahead are the head's, well behind the tail's
    ahead = dep.x_m[lb.rrh] > x + PANELS[0] + 100
    behind = dep.x_m[lb.rrh] < x + PANELS[1] - 100
    assert np.all(lb.panel[ahead] == 0) and np.all(lb.panel[behind] == 1)
    np.testing.assert_allclose(lb.d3d_m, np.where(lb.panel == 0, d_head, d_tail))
    # the tracker's geometric rule agrees away from the train's flank
    far = ahead | behind
    np.testing.assert_array_equal(facing_panel(x, dep.x_m[lb.rrh][far], dep.offset_m, PANELS), lb.panel[far])


@pytest.fixture(scope="module")
def panel_epochs():
    with open("config/config.yaml", encoding="utf-8") as fh:
        c = yaml.safe_load(fh)["nr"]
    c["antenna"]["train_panels_x_m"] = list(PANELS)
    scn = scenario_from_config(c)
    return simulate_epochs(scn, np.arange(2400, 2404), 7, spawn_key("nr", 0)), scn


def test_burst_toa_is_measured_at_the_facing_panel(panel_epochs):
    ds, scn = panel_epochs
    assert tuple(ds["train_panel_x"].values) == PANELS
    rob = ds.sel(receiver="robust")
    ok = np.isfinite(rob["toa_hat"].values) & (rob["best_score"].values > 8)  # clear detections
    err = (rob["toa_hat"].values - rob["toa_true"].values) * SPEED_OF_LIGHT_M_S
    # within a few samples of the stronger panel's range, not ~100 m off (the reference point)
    assert ok.sum() >= 8
    assert np.median(np.abs(err[ok])) < 1.5
    ref = scn.deployment.distance_3d_m(ds["x_true"].values[:, None], ds["rrh"].values)
    assert np.median(np.abs(rob["toa_hat"].values[ok] * SPEED_OF_LIGHT_M_S - ref[ok])) > 50


def _noiseless_panel_dataset(x_ref: float) -> xr.Dataset:
    """One epoch of exact AOD/TOA measurements taken at the facing panels."""
    dep = Deployment()
    cand = dep.nearest(x_ref, 6)
    panel = facing_panel(x_ref, dep.x_m[cand], dep.offset_m, PANELS)
    xp = x_ref + np.asarray(PANELS)[panel]
    d3 = dep.distance_3d_m(xp, cand)
    aod = dep.aod_rad(xp, cand)
    one = lambda a: a[None, :]  # noqa: E731
    return xr.Dataset(
        {
            "rrh": (("epoch", "cand"), one(cand)),
            "aod_hat": (("epoch", "cand"), one(aod)),
            "toa_hat": (("epoch", "cand"), one(d3 / SPEED_OF_LIGHT_M_S)),
            "peak": (("epoch", "cand"), one(-np.abs(dep.x_m[cand] - x_ref))),
            "train_panel_x": (("panel_id",), np.asarray(PANELS)),
        }
    )


@pytest.mark.parametrize("x_ref", [5_180.0, 5_430.0])
def test_lever_arm_recovers_the_reference_point(x_ref):
    dep = Deployment()
    ds = _noiseless_panel_dataset(x_ref)
    cfg = TrackerConfig(measurements="aod_toa", q=1.0, sigma_aod_rad=np.radians(0.5), sigma_toa_s=1e-9)
    dh = dep.h_bs_m - dep.h_ut_m
    fix = track_setup(ds, dep.x_m, dep.offset_m, dh, cfg, "peak", 3).meas.snapshot_fix
    p, _ = fix(0, x_ref)
    np.testing.assert_allclose(p, [x_ref, 0.0], atol=1e-3)
    # the point model (lever arm ignored) is off by tens of metres
    fix_point = track_setup(ds, dep.x_m, dep.offset_m, dh, cfg, "peak", 3, lever_arm=False).meas.snapshot_fix
    q, _ = fix_point(0, x_ref)
    assert np.hypot(q[0] - x_ref, q[1]) > 10.0
