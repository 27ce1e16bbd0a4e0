"""The filters stay consistent: NEES/NIS against chi-square bounds, PF close to KF."""

import numpy as np
import pytest
from scipy import stats

from railradio.tunnel.tracking import kf_track, pf_track, robust_variance


def _truth(rng, n=2000, dt=0.05, q=0.5):
    x = np.empty(n)
    v = np.empty(n)
    x[0], v[0] = 100.0, 60.0
    for t in range(1, n):
        a = q * rng.standard_normal()
        x[t] = x[t - 1] + v[t - 1] * dt + 0.5 * a * dt**2
        v[t] = v[t - 1] + a * dt
    return x, v


def test_kf_consistent_nees_and_nis(rng):
    dt, q, r = 0.05, 0.5, 4.0
    x, v = _truth(rng, dt=dt, q=q)
    z = x + np.sqrt(r) * rng.standard_normal(x.size)
    xe, ve, var, nis = kf_track(z, r, dt, q, (z[0], 0.0), (r, 100.0**2), gate_sigma=None)
    burn = 200
    nees = (xe[burn:] - x[burn:]) ** 2 / var[burn:]
    n = nees.size
    # mean NEES of a 1-D quantity over n (correlated) epochs: generous chi-square band
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], n) / n
    assert 0.5 * lo < nees.mean() < 1.5 * hi
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], n) / n
    assert lo < np.nanmean(nis[burn:]) < hi
    assert np.sqrt(np.mean((xe[burn:] - x[burn:]) ** 2)) < np.sqrt(r)  # it filters


def test_kf_gate_rejects_outliers_and_rigid_train(rng):
    dt, q, r = 0.05, 0.5, 1.0
    x, _ = _truth(rng, dt=dt, q=q)
    z = x + rng.standard_normal(x.size)
    z[500:505] += 300.0
    xe, *_ = kf_track(z, r, dt, q, (z[0], 0.0), (r, 100.0**2))
    assert np.max(np.abs(xe[450:600] - x[450:600])) < 5.0
    offs = np.array([0.0, 100.0, 200.0])
    zk = x[:, None] - offs + rng.standard_normal((x.size, 3))
    xr, *_ = kf_track(zk, r, dt, q, (zk[0, 0], 0.0), (r, 100.0**2), offsets_m=offs)
    xs, *_ = kf_track(zk[:, 0], r, dt, q, (zk[0, 0], 0.0), (r, 100.0**2))
    assert np.mean((xr[200:] - x[200:]) ** 2) < np.mean((xs[200:] - x[200:]) ** 2)


def test_pf_close_to_kf_and_reproducible(rng):
    dt, q, r = 0.05, 0.5, 4.0
    x, _ = _truth(rng, n=800, dt=dt, q=q)
    z = x + 2.0 * rng.standard_normal(x.size)
    xk, *_ = kf_track(z, r, dt, q, (z[0], 0.0), (r, 100.0**2), gate_sigma=None)
    xp, var = pf_track(z, r, dt, q, (z[0], 0.0), (r, 100.0**2), 1000, np.random.default_rng(5))
    xp2, _ = pf_track(z, r, dt, q, (z[0], 0.0), (r, 100.0**2), 1000, np.random.default_rng(5))
    np.testing.assert_array_equal(xp, xp2)
    rk = np.sqrt(np.mean((xk[100:] - x[100:]) ** 2))
    rp = np.sqrt(np.mean((xp[100:] - x[100:]) ** 2))
    assert rp < 1.3 * rk
    assert 0.3 < np.mean((xp[100:] - x[100:]) ** 2 / var[100:]) < 3.0


def test_robust_variance():
    e = np.random.default_rng(3).normal(0, 2.0, 20000)
    assert robust_variance(e) == pytest.approx(4.0, rel=0.05)
    with pytest.raises(ValueError):
        robust_variance(np.array([np.nan]))


def test_batch_kf_equals_filterpy_kf():
    """The vectorized KF of the Monte Carlo realizations reproduces filterpy's, gate and
    NaN epochs included, track by track."""
    from railradio.tunnel.tracking import kf_track_batch

    rng = np.random.default_rng(11)
    dt, q, r = 0.05, 0.5, 4.0
    t = np.arange(2000) * dt
    truth = 100.0 + 25.0 * t
    z = truth[:, None] + np.sqrt(r) * rng.standard_normal((t.size, 3))
    z[rng.random(z.shape) < 0.05] = np.nan
    z[500:510, 1] += 80.0  # outliers the gate must reject
    rt = r * (1.0 + rng.random(z.shape))
    xb = kf_track_batch(z, rt, dt, q, np.full(3, 100.0), (r, 100.0**2))
    for b in range(3):
        xk, *_ = kf_track(z[:, b], rt[:, b], dt, q, (100.0, 0.0), (r, 100.0**2))
        np.testing.assert_allclose(xb[:, b], xk, rtol=0, atol=1e-6)
    assert np.max(np.abs(xb[500:510, 1] - truth[500:510])) < 5.0


def test_systematic_resampler_matches_filterpy_and_uses_the_generator():
    """Our systematic resampler equals filterpy's for the same random offset, leaves numpy's
    global state alone, and is reproducible from the Generator."""
    from filterpy.monte_carlo import resampling

    from railradio.tunnel.tracking import systematic_resample_with

    w = np.random.default_rng(3).random(500) ** 4
    w /= w.sum()
    state = np.random.get_state()
    idx = systematic_resample_with(w, np.random.default_rng(9))
    assert np.array_equal(np.random.get_state()[1], state[1])
    u = np.random.default_rng(9).random()
    orig = resampling.random
    resampling.random = lambda: u  # filterpy reads its offset from the module-level random
    try:
        ref = resampling.systematic_resample(w)
    finally:
        resampling.random = orig
    np.testing.assert_array_equal(idx, ref)
    np.testing.assert_array_equal(idx, systematic_resample_with(w, np.random.default_rng(9)))
    with pytest.raises(ValueError, match="weights"):
        systematic_resample_with(np.array([0.5, -0.1]), np.random.default_rng(0))


def test_filters_started_from_the_first_fix_do_not_count_it_twice():
    """Started from the first fix (variance R, speed 0 +- 100 m/s) at 250 km/h, every track
    locks on when that fix is not used again; re-using it as a measurement makes the filter
    overconfident in a wrong speed and the gate then locks some tracks out."""
    from railradio.tunnel.tracking import kf_track, kf_track_batch

    rng = np.random.default_rng(11)
    dt, q, r, b = 0.1, 0.5, 1.0, 400
    t = np.arange(300) * dt
    truth = 500.0 + 69.4 * t
    z = truth[:, None] + np.sqrt(r) * rng.standard_normal((t.size, b))
    good = kf_track_batch(z, r, dt, q, z[0], (r, 100.0**2), start_at_first=True)
    twice = kf_track_batch(z, r, dt, q, z[0], (r, 100.0**2))
    assert np.all(np.abs(good[-1] - truth[-1]) < 5.0)
    assert np.mean(np.abs(twice[-1] - truth[-1]) > 50.0) > 0.01
    x, _, _, _ = kf_track(z[:, 0], r, dt, q, (z[0, 0], 0.0), (r, 100.0**2), start_at_first=True)
    np.testing.assert_allclose(x, good[:, 0], atol=1e-6)
