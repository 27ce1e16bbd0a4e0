"""The RTS smoother (railradio.nr.tracking.smoother) against filterpy's, on an EKF-like track."""

import numpy as np
from filterpy.kalman import KalmanFilter

from railradio.nr.tracking.dynamics import process_noise, transition
from railradio.nr.tracking.smoother import rts_smooth


def _filtered(rng, n=400, dt=0.1, q=0.5):
    """A constant-acceleration track along x filtered from noisy positions: states, covs."""
    f, qm = transition(dt), process_noise(dt, q)
    kf = KalmanFilter(dim_x=f.shape[0], dim_z=2)
    kf.F, kf.Q = f, qm
    kf.H = np.zeros((2, f.shape[0]))
    kf.H[0, 0] = kf.H[1, 1] = 1.0  # s = [x, y, vx, vy, ax, ay]
    kf.R = np.eye(2) * 4.0
    kf.P = np.eye(f.shape[0]) * 100.0
    x = np.zeros(f.shape[0])
    xs, ps = [], []
    for _ in range(n):
        x = f @ x + rng.multivariate_normal(np.zeros(f.shape[0]), qm)
        kf.predict()
        kf.update((kf.H @ x + rng.normal(0.0, 2.0, 2))[:, None])
        xs.append(kf.x.ravel().copy())
        ps.append(kf.P.copy())
    return np.array(xs), np.array(ps), f, qm


def test_equals_filterpys_rts_smoother():
    """Same recursion (Särkkä 2013, Th. 8.2): ours solves P⁻ C = F P instead of filterpy's explicit
    inverse, so the two agree to rounding, not bit for bit."""
    xs, ps, f, q = _filtered(np.random.default_rng(1))
    ours_x, ours_p = rts_smooth(xs, ps, f, q)
    ref_x, ref_p, _, _ = KalmanFilter(dim_x=f.shape[0], dim_z=2).rts_smoother(
        xs, ps, Fs=[f] * len(xs), Qs=[q] * len(xs)
    )
    np.testing.assert_allclose(ours_x, ref_x, rtol=0, atol=1e-9 * np.abs(ref_x).max())
    np.testing.assert_allclose(ours_p, ref_p, rtol=0, atol=1e-9 * np.abs(ref_p).max())
    assert not np.allclose(ours_x, xs)  # the smoother did something


def test_leading_epochs_without_a_track_stay_nan():
    """What filterpy's smoother cannot take: the epochs before the first fix are NaN."""
    xs, ps, f, q = _filtered(np.random.default_rng(2), n=50)
    xs[:5] = np.nan
    sx, sp = rts_smooth(xs, ps, f, q)
    assert np.isnan(sx[:5]).all() and np.isfinite(sx[5:]).all()
