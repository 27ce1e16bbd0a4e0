"""Fresnel coefficients of the concrete lining against hand values and limits."""

import numpy as np
import pytest

from railradio.tunnel.materials import CONCRETE_900MHZ, fresnel_te, fresnel_tm, reflection_loss_db


def test_normal_incidence_8db_for_concrete():
    # hand value: sqrt(5.31 - 0.60j) = 2.3057 - 0.1301j; |(1 - n)/(1 + n)|^2 = 1.7218/10.9446
    # = 0.15732 -> 8.03 dB (the source's 8 dB holds only at normal incidence)
    assert CONCRETE_900MHZ == complex(5.31, -0.60)
    for fn in (fresnel_te, fresnel_tm):
        loss = float(reflection_loss_db(fn(1.0)))
        assert loss == pytest.approx(8.03, abs=0.01)
        assert round(loss, 1) == 8.0
    # both polarizations coincide at normal incidence; with p = s x k the TM sign is opposite
    assert fresnel_tm(1.0) == pytest.approx(-fresnel_te(1.0), abs=1e-12)


def test_grazing_limits():
    # at grazing incidence (cos -> 0) both coefficients tend to -1 (0 dB loss) ...
    for fn in (fresnel_te, fresnel_tm):
        assert fn(0.0) == pytest.approx(-1.0, abs=1e-12)
    # ... linearly: Gamma_TE ~ -1 + 2 c / sqrt(eps - 1), Gamma_TM ~ -1 + 2 eps c / sqrt(eps - 1)
    c = 1e-4
    root = np.sqrt(CONCRETE_900MHZ - 1)
    assert fresnel_te(c) == pytest.approx(-1 + 2 * c / root, abs=1e-7)
    assert fresnel_tm(c) == pytest.approx(-1 + 2 * CONCRETE_900MHZ * c / root, abs=1e-6)
    # near grazing TE loses far less than the source's fixed 8 dB: 0.1-1.5 dB at 1-10 degrees
    graze = np.deg2rad([1.0, 10.0])
    loss = reflection_loss_db(fresnel_te(np.sin(graze)))
    assert 0.1 < loss[0] < 0.2 and 1.3 < loss[1] < 1.6


def test_brewster_angle_lossless():
    eps = 4.0
    cos_b = np.cos(np.arctan(np.sqrt(eps)))
    assert abs(fresnel_tm(cos_b, eps)) < 1e-12
    assert abs(fresnel_te(cos_b, eps)) > 0.3


def test_passive_walls_never_amplify():
    c = np.linspace(0, 1, 1001)
    for eps in (CONCRETE_900MHZ, complex(3.0, -2.0), complex(20.0, -0.01)):
        assert np.all(np.abs(fresnel_te(c, eps)) <= 1 + 1e-12)
        assert np.all(np.abs(fresnel_tm(c, eps)) <= 1 + 1e-12)


@pytest.mark.parametrize(
    ("cos_i", "eps"),
    [(1.2, CONCRETE_900MHZ), (-0.1, CONCRETE_900MHZ), (0.5, complex(0.5, 0)), (0.5, complex(5.0, 0.3))],
)
def test_bad_input_raises(cos_i, eps):
    with pytest.raises(ValueError):
        fresnel_te(cos_i, eps)


def test_circular_guide_attenuation_marcatili_schmeltzer():
    # 8.5 m concrete circle at 900 MHz: EH11 about 2.8 dB/km, below the equal-area square's
    # EH11; TE01 lower still (its nu = 1/sqrt(eps - 1) is the smallest); TM01 far higher;
    # the attenuation scales as lambda^2 / a^3
    from railradio.tunnel.materials import circular_attenuation_db_per_m, eh11_attenuation_db_per_m

    lam = 299_792_458.0 / 9e8
    eh11 = circular_attenuation_db_per_m(lam, 4.25, "EH11") * 1e3
    te01 = circular_attenuation_db_per_m(lam, 4.25, "TE01") * 1e3
    tm01 = circular_attenuation_db_per_m(lam, 4.25, "TM01") * 1e3
    side = 8.5 * np.sqrt(np.pi) / 2
    assert 2.7 < eh11 < 2.9
    assert te01 < eh11 < eh11_attenuation_db_per_m(lam, side, side) * 1e3 < tm01
    assert circular_attenuation_db_per_m(2 * lam, 8.5, "EH11") == pytest.approx(
        circular_attenuation_db_per_m(lam, 4.25, "EH11") * 4 / 8
    )
    with pytest.raises(ValueError, match="mode"):
        circular_attenuation_db_per_m(lam, 4.25, "HE99")
