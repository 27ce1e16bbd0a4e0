"""Fast fading at the random-access occasions (railradio.handover.fading): the Rician
distribution, Clarke's correlation between occasions, and the access stage reading it."""

import math

import numpy as np
import pytest
from scipy import stats
from scipy.special import j0

from railradio.handover.fading import clarke_factor, doppler_hz, power_gains_db
from railradio.handover.stages import STAGE_ACCESS, STAGE_NONE, execute_stages

from .test_stages import TIMES, V, _monitor


def test_clarke_factor_reproduces_the_autocorrelation():
    lf = clarke_factor(49, 583.0, 0.01)
    lag = np.abs(np.subtract.outer(np.arange(49), np.arange(49)))
    np.testing.assert_allclose(lf @ lf.T, j0(2 * math.pi * 583.0 * 0.01 * lag), atol=1e-8)
    # a slow train: R tends to all ones (singular); the factor still exists
    lf = clarke_factor(49, 0.5, 0.01)
    assert np.all(np.isfinite(lf))
    with pytest.raises(ValueError, match="dt_s"):
        clarke_factor(4, 10.0, 0.0)


@pytest.mark.parametrize("k_db", [None, 7.0])
def test_power_gain_is_rician_with_unit_mean(k_db):
    rng = np.random.default_rng(11)
    white = rng.standard_normal((40_000, 3, 2))
    g_db = power_gains_db(white, rng.random(40_000), k_db, 300.0, 0.01, np.ones(40_000), 0.015)
    p = 10 ** (g_db / 10)
    assert abs(p.mean() - 1.0) < 0.02
    k = 0.0 if k_db is None else 10 ** (k_db / 10)
    # |h|^2 of a Rician channel: noncentral chi-square, 2 degrees of freedom, scaled
    rice = stats.ncx2(df=2, nc=2 * k, scale=1 / (2 * (k + 1))) if k > 0 else stats.expon()
    for occ in range(3):
        assert stats.kstest(p[:, occ], rice.cdf).pvalue > 1e-3


def test_occasions_are_correlated_as_clarke_says():
    """At 100 km/h and 1.8 GHz (f_D = 167 Hz) occasions 10 ms apart are not independent:
    the diffuse parts' correlation is J0(2π f_D 10 ms) = −0.24."""
    f_d = doppler_hz(100 / 3.6, 1.8e9)
    rng = np.random.default_rng(2)
    white = rng.standard_normal((200_000, 2, 2))
    lf = clarke_factor(2, f_d, 0.01)
    z = (white[..., 0] + 1j * white[..., 1]) / math.sqrt(2) @ lf.T
    rho = np.mean(z[:, 0] * np.conj(z[:, 1])).real
    assert abs(rho - j0(2 * math.pi * f_d * 0.01)) < 0.01
    assert j0(2 * math.pi * f_d * 0.01) < -0.2


def test_one_look_per_occasion_lets_access_through_a_weak_local_mean():
    """The target's local mean 3 dB below Q_out at every occasion (and strong from 60 m on,
    so the new link holds): on local means alone access fails (T304 expires); with Rayleigh
    fading one occasion in e^(-2) rises above it."""
    mon = _monitor(lambda x: 20.0 + 0 * x, lambda x: np.where(x < 560.0, -11.0, 10.0))  # Q_out = -8 dB
    n = 200
    run, hb = np.zeros(n, dtype=np.int64), np.full(n, 500.0)
    flat = execute_stages(mon, TIMES, run, hb, V)
    assert np.all(flat.stage == STAGE_ACCESS)
    rng = np.random.default_rng(5)
    n_occ = TIMES.n_occasions
    g_t = power_gains_db(rng.standard_normal((n, n_occ, 2)), rng.random(n), None, 500.0, 0.01, np.ones(n), 0.015)
    faded = execute_stages(mon, TIMES, run, hb, V, (np.zeros_like(g_t), g_t))
    assert np.mean(faded.stage[faded.success] == STAGE_NONE) == 1.0
    # first success at occasion i with probability (1 - q)^i q, q = P(|h|^2 >= 10^(3/10)) = e^-2
    q = math.exp(-(10**0.3))
    assert abs(np.mean(faded.occasions == 1) - q) < 0.07
    assert faded.success.mean() > 0.95
