"""The wideband receiver over Monte Carlo realizations, its cable-model errors, and the
thresholded delay spread (small CI tunnel)."""

import dataclasses

import numpy as np
import pytest

from railradio.rng import make_rng
from railradio.tunnel.delay_profile import received_spreads, rms_spread_s
from railradio.tunnel.measurement import shadow_field
from railradio.tunnel.simulate import run_train
from railradio.tunnel.study import (
    cable_from_config,
    measurement_from_config,
    run_setup,
    train_from_config,
    tunnel_from_config,
)
from railradio.tunnel.wideband import tone_response, wideband_candidates, wideband_delays, wideband_view
from railradio.tunnel.wideband_runs import CableModelError


def test_batched_realizations_equal_single_ones(ci):
    """R realizations synthesized together (one gather, one matrix product per position)
    give each realization's delays as computed alone, and shadowing changes them."""
    cfg, table = ci
    tun = tunnel_from_config(cfg, table.attrs["shape"])
    cab, mm = cable_from_config(cfg), wideband_view(table, measurement_from_config(cfg))
    tones = tone_response(table, mm)
    x = np.linspace(300.0, 1700.0, 97)
    sh = [shadow_field(make_rng(5, (1, r)), tun.slot_x_m.size, tun.length_m, 4.0, 10.0) for r in range(3)]
    batch = wideband_delays(table, tun, cab, x, [make_rng(9, (r,)) for r in range(3)], mm, tones, shadow_db=sh)
    assert batch.shape == (3, x.size)
    for r in range(3):
        alone = wideband_delays(table, tun, cab, x, make_rng(9, (r,)), mm, tones, shadow_db=sh[r])
        np.testing.assert_allclose(batch[r], alone, rtol=0, atol=1e-15)
    plain = wideband_delays(table, tun, cab, x, make_rng(9, (0,)), mm, tones)
    assert np.max(np.abs(plain - batch[0])) > 1e-10
    with pytest.raises(ValueError, match="shadow_db"):
        wideband_delays(table, tun, cab, x, [make_rng(9, (0,))], mm, tones, shadow_db=sh)


def test_cable_model_errors_move_the_ranges_as_stated(ci):
    """A velocity factor off by delta scales every cable range by (1 + delta); a feed's delay
    error d moves its candidates by v c d toward the feed."""
    cfg, _ = ci
    tun = tunnel_from_config(cfg, "rect")
    cab = cable_from_config(cfg)
    feeds = cab.feed_x_m(tun.length_m)
    tau = np.array([0.5e-6, 1.0e-6])  # ranges inside the first section (no clipping)

    def ranges(**kw):  # cable range from the first feed, on its upstream side [epoch]
        return feeds[0] - wideband_candidates(tau, tun, cab, **kw)[:, 0]

    r0 = ranges()
    v, d = CableModelError(velocity_factor_rel=0.02).receiver_model(cab, feeds.size, None)
    np.testing.assert_allclose(ranges(velocity_factor=v, feed_delay_s=d), 1.02 * r0, rtol=1e-12)
    v, d = CableModelError(feed_delay_max_s=32.5e-9).receiver_model(cab, feeds.size, np.random.default_rng(1))
    assert v == cab.velocity_factor and d.shape == feeds.shape and np.all((d != 0) & (np.abs(d) <= 32.5e-9))
    r2 = ranges(velocity_factor=v, feed_delay_s=d)
    np.testing.assert_allclose(r0 - r2, v * 299_792_458.0 * d[0], rtol=1e-9)
    with pytest.raises(ValueError, match="feed_delay_s"):
        wideband_candidates(tau, tun, cab, feed_delay_s=np.zeros(feeds.size + 1))
    with pytest.raises(ValueError, match="velocity_factor_rel"):
        CableModelError(velocity_factor_rel=1.5)
    with pytest.raises(ValueError, match="feed_delay_max_s"):
        CableModelError(feed_delay_max_s=-1.0)


def test_wideband_realizations_and_cases(ci):
    """The wideband run pools R realizations (realization 0 is the full run's KF); the low-speed
    case runs at the stated speed; a velocity-factor error (the same draws) worsens the track."""
    cfg, table = ci
    tun = tunnel_from_config(cfg, table.attrs["shape"])
    cab, mm = cable_from_config(cfg), measurement_from_config(cfg)
    tr = train_from_config(cfg, "hst")
    ds = run_train(table, tun, cab, tr, mm, "physical", "wideband", cfg["tracking"], 3, realizations=3)
    assert ds["rep_err"].shape[0] == 3
    np.testing.assert_array_equal(ds["rep_err_head"].values[0], ds["kf_err_head"].values)
    assert not np.allclose(ds["rep_err"].values[1], ds["rep_err"].values[2])
    slow, err = run_setup(cfg, "hst", "physical_wideband_slow")
    assert slow.speed_kmh == cfg["cases"]["low_speed_kmh"] and err is None
    _, err = run_setup(cfg, "hst", "physical_wideband_vf")
    big = dataclasses.replace(err, velocity_factor_rel=0.05)
    dv = run_train(table, tun, cab, tr, mm, "physical", "wideband", cfg["tracking"], 3, realizations=2, cable_error=big)
    assert np.percentile(dv["rep_err"].values, 95) > np.percentile(ds["rep_err"].values[:2], 95)
    with pytest.raises(ValueError, match="setup"):
        run_setup(cfg, "hst", "physical_ultrawide")


def test_rms_spread_threshold_drops_weak_arrivals():
    delay = np.array([0.0, 100e-9, 1000e-9])
    pdp = np.array([[1.0, 0.0, 1e-3]])  # an arrival 30 dB down, 1 us late
    full = rms_spread_s(pdp, delay)[0]
    p = 1e-3 / 1.001
    assert full == pytest.approx(1e-6 * np.sqrt(p * (1 - p)), rel=1e-9)
    assert rms_spread_s(pdp, delay, 25.0)[0] == 0.0  # below 25 dB: dropped
    assert rms_spread_s(pdp, delay, 31.0)[0] == pytest.approx(full)
    with pytest.raises(ValueError, match="threshold_db"):
        rms_spread_s(pdp, delay, 0.0)


def test_unthresholded_profile_matches_the_moment_spread(ci):
    """The binned all-slot profile's RMS spread equals the map's moment-based one within the
    rounding of absolute delays to the 10 ns grid; thresholds only shorten it."""
    from railradio.tunnel.channel import received

    cfg, table = ci
    tun = tunnel_from_config(cfg, table.attrs["shape"])
    cab = cable_from_config(cfg)
    x = np.linspace(100.0, tun.length_m - 100.0, 41)
    sp = received_spreads(table, tun, cab, x, (25.0, 30.0))
    ref = received(table, tun, cab, x).delay_rms_s
    np.testing.assert_allclose(sp[None], ref, rtol=0.02, atol=3e-9)
    assert np.all(sp[25.0] <= sp[30.0] + 1e-15) and np.all(sp[30.0] <= sp[None] + 1e-12)
