"""Monte Carlo realizations and delay-error models of a train crossing (small CI tunnel)."""

import numpy as np
import pytest

from railradio.tunnel.measurement import MeasurementModel, delay_error_field
from railradio.tunnel.sensitivity import sensitivity_cases
from railradio.tunnel.simulate import calibrate_separable, kf_realizations, run_train
from railradio.tunnel.study import cable_from_config, measurement_from_config, train_from_config, tunnel_from_config


def test_delay_error_fields():
    rng = np.random.default_rng(1)
    white = MeasurementModel(delay_sigma_s=20e-9)
    assert delay_error_field(rng, 10, 100.0, white) is None
    bias = delay_error_field(rng, 4000, 100.0, MeasurementModel(delay_sigma_s=20e-9, delay_error="slot_bias"))
    assert np.all(bias == bias[:, :1])  # constant along the track
    assert np.std(bias[:, 0]) == pytest.approx(20e-9, rel=0.05)
    ar = delay_error_field(
        rng, 2000, 200.0, MeasurementModel(delay_sigma_s=20e-9, delay_error="ar1", delay_corr_m=20.0)
    )
    assert np.std(ar) == pytest.approx(20e-9, rel=0.05)
    rho = np.mean(ar[:, 100] * ar[:, 120]) / np.mean(ar[:, 100] ** 2)
    assert rho == pytest.approx(np.exp(-1.0), abs=0.06)  # exp(-20 m / 20 m)
    with pytest.raises(ValueError, match="delay_error"):
        MeasurementModel(delay_error="pink")
    with pytest.raises(ValueError, match="delay_corr_m"):
        MeasurementModel(delay_corr_m=0.0)


def test_realizations_reproduce_the_main_run_and_differ(ci):
    cfg, table = ci
    tun = tunnel_from_config(cfg, table.attrs["shape"])
    cab, mm, tr = cable_from_config(cfg), measurement_from_config(cfg), train_from_config(cfg, "hst")
    ds = run_train(table, tun, cab, tr, mm, "physical", "separable", cfg["tracking"], 3, realizations=3)
    assert ds["rep_err"].shape[0] == 3
    np.testing.assert_array_equal(ds["rep_err_head"].values[0], ds["kf_err_head"].values)
    # the vectorized KF on realization 0 equals filterpy's main run
    eh, et = kf_realizations(table, tun, cab, tr, mm, "physical", cfg["tracking"], 3, ds.attrs["r0_m2"], [0, 2])
    np.testing.assert_allclose(eh[0], ds["kf_err_head"].values, atol=1e-6)
    np.testing.assert_allclose(et[1], ds["rep_err_tail"].values[2], atol=1e-12)
    assert not np.allclose(ds["rep_err"].values[1], ds["rep_err"].values[2])
    with pytest.raises(ValueError, match="realizations"):
        run_train(table, tun, cab, tr, mm, "physical", "separable", cfg["tracking"], 3, realizations=0)


def test_correlated_delay_error_is_not_averaged_away(ci):
    """With the same sigma, a per-slot bias survives the filter; white errors do not."""
    cfg, table = ci
    tun = tunnel_from_config(cfg, table.attrs["shape"])
    cab, tr = cable_from_config(cfg), train_from_config(cfg, "hst")
    p95 = {}
    for e in ("white", "slot_bias"):
        mm = measurement_from_config(cfg, delay_error=e)
        r0 = calibrate_separable(table, tun, cab, tr, mm, "physical", cfg["tracking"], 3)
        eh, _ = kf_realizations(table, tun, cab, tr, mm, "physical", cfg["tracking"], 3, r0, range(3))
        p95[e] = np.percentile(eh, 95)
    assert p95["slot_bias"] > 1.5 * p95["white"]
    assert set(sensitivity_cases(cfg)) >= {"delay_error_ar1", "shadow_sigma_db_3", "delay_sigma_ns_50"}


def test_wideband_peak_recovers_a_single_path_delay():
    """The CIR-peak estimator on one slot's line-of-sight ray (absorbing walls, one slot in
    the window, no noise) recovers the closed-form delay - slot's cable delay + distance / c -
    within the parabolic-interpolation bound derived in peak_interp_bound_s (~0.014 ns at
    5 MHz, 16x oversampling): the band-limited pulse itself has no bias; the calibrated
    peak bias of the full channel comes from the superposition of slots and wall rays."""
    from railradio.constants import SPEED_OF_LIGHT_M_S
    from railradio.tunnel.channel import offset_grid_m, tabulate
    from railradio.tunnel.geometry import Cable, Tunnel
    from railradio.tunnel.rays import image_families
    from railradio.tunnel.wideband import peak_interp_bound_s, wideband_delays

    tun, cab = Tunnel(length_m=2000.0, shape="rect"), Cable()
    step = 0.04
    los = tabulate(
        image_families(tun, 0),
        tun,
        cab,
        offset_grid_m(step, 20.0, tun.slot_spacing_m),
        eps=None,
        polarization="paraxial",
        n_delay_bins=4,
        local_mean_window_m=13.3,
    )
    mm = MeasurementModel(window_m=9.99, bandwidth_hz=5e6, n_tones=64)
    rng = np.random.default_rng(5)
    slot = 20.0 * rng.integers(5, 95, 400)
    dx = step * rng.integers(-249, 250, slot.size)  # on the table grid, nearest slot only
    x = slot + dx
    tau = wideband_delays(los, tun, cab, x, None, mm, thermal_noise=False)
    want = cab.cable_delay_s(slot, tun.length_m) + np.hypot(dx, tun.cross_distance_m) / SPEED_OF_LIGHT_M_S
    bound = peak_interp_bound_s(mm.bandwidth_hz, 16)
    assert bound < 0.02e-9
    assert np.max(np.abs(tau - want)) <= bound
    # coarser oversampling: the error grows as os^-3 and stays within its own bound
    tau4 = wideband_delays(los, tun, cab, x, None, mm, thermal_noise=False, oversample=4)
    assert np.max(np.abs(tau4 - want)) <= peak_interp_bound_s(mm.bandwidth_hz, 4)
    assert np.max(np.abs(tau4 - want)) > bound
