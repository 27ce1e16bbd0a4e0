"""Tunnel geometry, cable and the slot-chain calibration to the coupling loss."""

import math

import numpy as np
import pytest

from railradio.tunnel.geometry import Cable, Tunnel, equal_area_side_m


def test_equal_area_square_and_slot_line():
    t = Tunnel()
    assert equal_area_side_m(8.5) == pytest.approx(7.533, abs=1e-3)  # D sqrt(pi)/2
    assert equal_area_side_m(8.5) ** 2 == pytest.approx(t.area_m2)
    assert t.slot_x_m.size == 250 and t.slot_x_m[-1] == 4980.0  # x_i = i dx, i < 250 [source]
    assert t.slot_yz == (pytest.approx(0.85), 0.0)
    assert t.with_shape("rect").slot_yz[0] == pytest.approx(0.7533, abs=1e-4)


@pytest.mark.parametrize("g_ref_dbi", [2.15, 0.0])
def test_slot_chain_reproduces_coupling_loss_at_2m(g_ref_dbi):
    """Geometry eq. (1): the along-cable mean of the incoherent free-space sum of a long
    slot chain, seen 2 m from the cable by the IEC 61196-4 reference antenna (a lambda/2
    dipole, +2.15 dBi), equals P_c - L_c(2 m) (L_c(2 m) = 85 + 10 lg 2 = 88.01 dB); the
    isotropic (0 dBi) train antenna of the study reads 2.15 dB less.  The 20 m spacing
    makes the level ripple along the cable by about +-5 dB at 2 m (slots are points)."""
    cab = Cable(loss_db_per_m=0.0, coupling_ref_gain_dbi=g_ref_dbi)
    s, d, lam = 20.0, 2.0, cab.wavelength_m
    p_slot = 10 ** (cab.slot_eirp_offset_db(s) / 10)  # per watt in the cable
    xs = np.arange(-5000, 5001) * s  # 200 km of cable: truncation < 1e-4 dB
    x = np.linspace(0, s, 2001)[:-1]
    p = p_slot * (lam / (4 * math.pi)) ** 2 * np.sum(1 / (d**2 + (x[:, None] - xs) ** 2), axis=1)
    mean_db = 10 * np.log10(p.mean())  # isotropic receiver
    assert mean_db + g_ref_dbi == pytest.approx(-(85 + 10 * math.log10(2)), abs=0.01)
    assert cab.slot_eirp_offset_db(s) == pytest.approx(
        Cable(loss_db_per_m=0.0, coupling_ref_gain_dbi=0.0).slot_eirp_offset_db(s) - g_ref_dbi, abs=1e-12
    )
    ripple = 10 * np.log10(p / p.mean())
    assert 4.0 < ripple.max() < 6.5 and -6.5 < ripple.min() < -4.0


def test_cable_feeds_loss_and_delay():
    cab = Cable()
    feeds = cab.feed_x_m(5000.0)
    np.testing.assert_allclose(feeds, [500, 1500, 2500, 3500, 4500])
    assert cab.cable_power_dbm(500.0, 5000.0) == pytest.approx(30.0)
    assert cab.cable_power_dbm(1000.0, 5000.0) == pytest.approx(30.0 - 12.5)  # 500 m at 2.5 dB/100 m
    assert cab.cable_delay_s(1000.0, 5000.0) == pytest.approx(500 / (0.88 * 299_792_458.0))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"shape": "oval"}, "shape"),
        ({"rx_y_m": 9.0}, "outside"),
        ({"slot_height_frac": 1.5}, "slot_height_frac"),
        ({"length_m": -1.0}, "length_m"),
    ],
)
def test_bad_geometry_raises(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Tunnel(**kwargs)


def test_bad_cable_raises():
    with pytest.raises(ValueError, match="velocity_factor"):
        Cable(velocity_factor=1.3)
