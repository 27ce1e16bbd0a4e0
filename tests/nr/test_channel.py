"""Channel: TDL-D against an independent transcription, path loss against hand values,
fading statistics against theory (tolerances named below)."""

import numpy as np
import pytest
from scipy import special, stats

from railradio.nr.channel.tdl import (
    breakpoint_distance_m,
    pathloss_umi_los_db,
    shadowing_field_db,
    sos_taps,
    tdl_profile,
)

# TR 38.901 v17 Table 7.7.2-4, TDL-D, transcribed independently of the code:
# (normalized delay, power dB); the first row is the LOS (specular) part of tap 1.
TDL_D_INDEPENDENT = [
    (0.0, -0.2),
    (0.0, -13.5),
    (0.035, -18.8),
    (0.612, -21.0),
    (1.363, -22.8),
    (1.405, -17.9),
    (1.804, -20.1),
    (2.596, -21.9),
    (1.775, -22.9),
    (4.042, -27.8),
    (7.937, -23.6),
    (9.424, -24.8),
    (9.708, -30.0),
    (12.525, -27.7),
]
KS_ALPHA = 1e-3  # statistical tests reject a correct model 0.1 % of the time
POWER_REL_TOL = 0.05  # tap power within 5 % (M sinusoids x many independent draws)


def test_tdl_d_matches_independent_transcription():
    p = tdl_profile("TDL-D", 20e-9)
    raw = np.array([10 ** (db / 10) for _, db in TDL_D_INDEPENDENT])
    assert 10 * np.log10(raw.sum()) == pytest.approx(0.32, abs=0.01)  # the table sums to +0.32 dB
    raw /= raw.sum()
    assert p.los_power == pytest.approx(raw[0], rel=1e-12)
    np.testing.assert_allclose(p.powers, raw[1:], rtol=1e-12)
    np.testing.assert_allclose(p.delays_s, [d * 20e-9 for d, _ in TDL_D_INDEPENDENT[1:]], rtol=1e-12)
    assert p.rice_k_db == pytest.approx(13.3, abs=1e-9)
    assert 10 * np.log10(p.los_power / p.powers.sum()) == pytest.approx(9.0, abs=0.05)
    with pytest.raises(ValueError, match="TDL profile"):
        tdl_profile("TDL-Q", 20e-9)


def test_pathloss_hand_values():
    # d'_BP = 4 * 9 * 1.5 * 30e9 / c = 5403.7 m
    assert breakpoint_distance_m(10.0, 2.5, 30e9) == pytest.approx(5403.74, abs=0.01)
    # PL1 at d3D = 100 m, 30 GHz: 32.4 + 42 + 29.542 = 103.942 dB
    assert float(pathloss_umi_los_db(100.0, 99.0, 30e9, 10, 2.5)) == pytest.approx(103.942, abs=1e-3)
    # PL2 at d3D = 6000 m: 32.4 + 40*3.77815 + 29.5424 - 9.5*log10(5403.74^2 + 56.25)
    pl2 = 32.4 + 40 * np.log10(6000) + 20 * np.log10(30) - 9.5 * np.log10(5403.74**2 + 7.5**2)
    assert float(pathloss_umi_los_db(6000.0, 6000.0, 30e9, 10, 2.5)) == pytest.approx(pl2, abs=1e-3)
    with pytest.raises(ValueError):
        pathloss_umi_los_db(0.0, 0.0, 30e9, 10, 2.5)


def test_shadowing_field_statistics():
    rng = np.random.default_rng(3)
    f = shadowing_field_db(rng, 400_000, 4.0, 10.0)
    assert f.std() == pytest.approx(4.0, rel=0.03)
    lag = 10  # 10 m: correlation exp(-1)
    rho = np.corrcoef(f[:-lag], f[lag:])[0, 1]
    assert rho == pytest.approx(np.exp(-1), abs=0.03)


def test_rayleigh_taps_power_amplitude_and_doppler_autocorrelation():
    rng = np.random.default_rng(11)
    f_d = 10e3
    powers = np.array([0.5, 0.1])
    # many independent processes at one time: power and amplitude distribution
    a = np.concatenate([sos_taps(rng, powers, f_d, np.array([0.0, 1.3e-3]), 16) for _ in range(3000)])
    for l, p in enumerate(powers):
        assert np.mean(np.abs(a[:, l]) ** 2) == pytest.approx(p, rel=POWER_REL_TOL)
        amp = np.abs(a[::2, l]) / np.sqrt(p / 2)
        assert stats.kstest(amp, "rayleigh").pvalue > KS_ALPHA
    # time autocorrelation against J0(2π f_D τ), averaged over realizations
    t = np.arange(64) * 5e-6
    acc = np.zeros(t.size, dtype=complex)
    n_real = 2000
    for _ in range(n_real):
        x = sos_taps(rng, np.array([1.0]), f_d, t, 16)[:, 0]
        acc += x * np.conj(x[0])
    acc /= n_real
    theory = special.j0(2 * np.pi * f_d * t)
    assert np.max(np.abs(acc.real - theory)) < 0.06  # ~3 standard errors of 2000 draws


def test_rice_first_tap_k_factor():
    """Tap 1 = LOS (fixed amplitude) + Rayleigh: Rice with K = 13.3 dB."""
    p = tdl_profile("TDL-D", 20e-9)
    rng = np.random.default_rng(5)
    diffuse = np.concatenate([sos_taps(rng, p.powers[:1], 1e3, np.array([0.0]), 16)[:, 0] for _ in range(20000)])
    tap1 = np.sqrt(p.los_power) + diffuse
    k = 10 ** (p.rice_k_db / 10)
    b = np.sqrt(2 * k)  # scipy rice shape for unit-scale Rayleigh part
    scale = np.sqrt(p.powers[0] / 2)
    assert stats.kstest(np.abs(tap1) / scale, "rice", args=(b,)).pvalue > KS_ALPHA
