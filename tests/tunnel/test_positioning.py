"""Positioning with noiseless measurements recovers the truth; GDOP, CEP."""

import numpy as np
import pytest

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.tunnel.geometry import Cable, Tunnel
from railradio.tunnel.measurement import MeasurementModel
from railradio.tunnel.positioning import cep, gain_to_offset_m, gdop_source, gdop_tdoa_along, rssi_ls, tdoa_gauss_newton
from railradio.tunnel.simulate import Train
from railradio.tunnel.wideband import wideband_candidates

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
    # source's GDOP: four slots symmetric around the receiver at the same depth
    g = gdop_source(np.array([0.0]), 4.0, np.array([[-20.0, -10.0, 10.0, 20.0]]), 0.85)
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


def _crossing(train_len=200.0, k=4, step=0.5):
    tun, cab = Tunnel(), Cable()
    tr = Train("t", train_len, 100.0, k)
    head = np.arange(train_len, tun.length_m, step)
    x_rx = head[:, None] - tr.receiver_offsets_m[None, :]
    tau = cab.cable_delay_s(x_rx, tun.length_m) + tun.cross_distance_m / SPEED_OF_LIGHT_M_S
    cand = np.stack([wideband_candidates(tau[:, j], tun, cab) for j in range(k)], axis=1)
    return tun, cab, tr, head, x_rx, cand


def test_ambiguity_resolved_from_the_measurements_alone():
    """Noiseless delays over a whole crossing (every feed, both sides, section ends): the
    receivers' delay pattern and continuity from the first section give the true side and
    feed at every epoch, without the truth; a flipped fix is counted as wrong."""
    from railradio.tunnel.wideband import ambiguity_wrong, resolve_ambiguity

    tun, cab, tr, head, x_rx, cand = _crossing()
    h, fix = resolve_ambiguity(cand, tr.receiver_offsets_m, cab.feed_spacing_m, (0.0, cab.feed_spacing_m), 20.0)
    np.testing.assert_allclose(h, head, atol=1e-6)
    np.testing.assert_allclose(fix, x_rx, atol=1e-6)
    assert not ambiguity_wrong(cand, fix, x_rx, 20.0).any()
    # the mirror image about the feed is a different candidate far from the truth: counted
    flipped = fix.copy()
    i = np.argmin(np.abs(head - 800.0))  # head 300 m past the feed at 500 m
    flipped[i, 0] = 2 * 500.0 - fix[i, 0]
    assert ambiguity_wrong(cand, flipped, x_rx, 20.0)[i, 0]
    assert ambiguity_wrong(cand, flipped, x_rx, 20.0).sum() == 1


def test_ambiguity_robust_to_one_wrong_peak_and_bad_input():
    from railradio.tunnel.wideband import resolve_ambiguity

    tun, cab, tr, head, x_rx, cand = _crossing(step=5.0)
    bad = cand.copy()
    bad[:, 1, :] = np.clip(bad[:, 1, :] + 60.0, 0, tun.length_m)  # one receiver's peak 60 m off
    h, fix = resolve_ambiguity(bad, tr.receiver_offsets_m, cab.feed_spacing_m, (0.0, cab.feed_spacing_m), 20.0)
    # the other three receivers agree: the head stays right wherever the sides are apart
    far = np.abs(np.abs(x_rx[:, 0] - 500.0) % 1000.0) > 60.0
    assert np.all(np.abs(h - head)[far] < 1e-6)  # (without the truncation: 8 % wrong)
    with pytest.raises(ValueError, match="offsets_m"):
        resolve_ambiguity(cand, np.zeros(3), 1000.0, (0.0, 1000.0), 20.0)
    with pytest.raises(ValueError, match="gate_m"):
        resolve_ambiguity(cand, tr.receiver_offsets_m, 1000.0, (0.0, 1000.0), 0.0)
