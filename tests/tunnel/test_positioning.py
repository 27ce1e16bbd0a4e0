"""Positioning with noiseless measurements recovers the truth; GDOP, CEP."""
import numpy as np
import pytest

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.tunnel.positioning import (cep, gain_to_offset_m, gdop_seed, gdop_tdoa_along,
                                          rssi_ls, tdoa_gauss_newton)
from railradio.tunnel.simulate import MeasurementModel, Train, wideband_candidates
from railradio.tunnel.geometry import Cable, Tunnel

H = 3.15


def _slots(x, n=8, spacing=20.0):
    near = np.round(x / spacing) * spacing
    return near[:, None] + spacing * (np.arange(n) - n // 2)[None, :]


def test_noiseless_rssi_ls_and_tdoa_recover_truth(rng):
    x = rng.uniform(200, 4800, 500)
    xs = _slots(x)
    d = np.sqrt((x[:, None] - xs) ** 2 + H**2)
    np.testing.assert_allclose(rssi_ls(xs, d, H), x, atol=1e-8)
    rd = d[:, 1:] - d[:, :1]
    x_gn, var = tdoa_gauss_newton(x + rng.uniform(-60, 60, x.size), xs, rd, H, 6.0)
    np.testing.assert_allclose(x_gn, x, atol=1e-6)
    assert np.all(var > 0)


def test_tdoa_noise_matches_its_predicted_variance(rng):
    x = np.full(4000, 1003.0)
    xs = _slots(x)
    sig_tau = 20e-9
    tau = np.sqrt((x[:, None] - xs) ** 2 + H**2) / SPEED_OF_LIGHT_M_S + sig_tau * rng.standard_normal(xs.shape)
    rd = SPEED_OF_LIGHT_M_S * (tau[:, 1:] - tau[:, :1])
    x_gn, var = tdoa_gauss_newton(x, xs, rd, H, SPEED_OF_LIGHT_M_S * sig_tau)
    assert np.std(x_gn - x) == pytest.approx(np.sqrt(var.mean()), rel=0.1)
    gd = gdop_tdoa_along(x_gn[:1], xs[:1], H)[0]
    assert gd * SPEED_OF_LIGHT_M_S * sig_tau == pytest.approx(np.sqrt(var.mean()), rel=0.05)


def test_gain_inversion_and_gdop_and_cep():
    off = np.linspace(0, 100, 101)
    curve = -40 - 20 * np.log10(np.hypot(off, H))
    np.testing.assert_allclose(gain_to_offset_m(curve[[5, 50]], off, curve), [5.0, 50.0], atol=1e-6)
    # seed's GDOP: four slots symmetric around the receiver at the same depth
    g = gdop_seed(np.array([0.0]), 4.0, np.array([[-20.0, -10.0, 10.0, 20.0]]), 0.85)
    t = np.arctan2(0.85 - 4.0, np.array([-20.0, -10.0, 10.0, 20.0]))
    a = np.column_stack([np.cos(t), np.sin(t)])
    assert g[0] == pytest.approx(np.sqrt(np.trace(np.linalg.inv(a.T @ a))))
    assert cep(1.0, 2.0) == pytest.approx(1.77)


def test_wideband_cable_ranging_noiseless():
    tun, cab = Tunnel(), Cable()
    x = np.array([700.0, 1234.0, 4100.0])
    tau = cab.cable_delay_s(x, tun.length_m) + tun.cross_distance_m / SPEED_OF_LIGHT_M_S
    cand = wideband_candidates(tau, tun, cab)
    assert np.all(np.min(np.abs(cand - x[:, None]), axis=1) < 1e-6)


def test_train_receivers_and_bad_models():
    assert Train("hst", 200.0, 250.0, 4).receiver_offsets_m.tolist() == pytest.approx([0, 200 / 3, 400 / 3, 200])
    with pytest.raises(ValueError, match="n_receivers"):
        Train("x", 100.0, 50.0, 1)
    with pytest.raises(ValueError, match="n_slots"):
        MeasurementModel(n_slots=2)
    with pytest.raises(ValueError):
        rssi_ls(np.zeros((3, 1)), np.zeros((3, 1)), H)
