"""Tracking along the track: Kalman filter and particle filter (filterpy) [source 7.2].

State [x, v] along the track (the source's eq. 7.2.1 state [x, vx, y, vy] reduced to the
track: the cross-section position is known), constant velocity with white acceleration
noise of standard deviation ``accel_sigma``: Q = sigma_a^2 [[dt^4/4, dt^3/2], [dt^3/2, dt^2]].
Measurements are snapshot positions (one per receiver) with variance R from a separate
calibration run.  The rigid-train option stacks all K receivers: receiver k measures
x_head - k L / (K - 1).
"""

from __future__ import annotations

import numpy as np
from filterpy.kalman import KalmanFilter
from scipy.stats import median_abs_deviation


def _cv_model(dt_s: float, accel_sigma: float) -> tuple[np.ndarray, np.ndarray]:
    if dt_s <= 0 or accel_sigma <= 0:
        raise ValueError("dt_s and accel_sigma must be positive")
    f = np.array([[1.0, dt_s], [0.0, 1.0]])
    g = np.array([[dt_s**2 / 2.0], [dt_s]])
    return f, accel_sigma**2 * (g @ g.T)


def _as_candidates(z_m) -> np.ndarray:
    z = np.asarray(z_m, dtype=float)
    if z.ndim == 1:
        return z[:, None, None]
    if z.ndim == 2:
        return z[:, :, None]
    if z.ndim == 3:
        return z
    raise ValueError("z_m must be [T], [T, K] or [T, K, C]")


def kf_track(
    z_m: np.ndarray,
    r_m2,
    dt_s: float,
    accel_sigma: float,
    x0: tuple[float, float],
    p0: tuple[float, float],
    offsets_m: np.ndarray | None = None,
    gate_sigma: float | None = 4.0,
    start_at_first: bool = False,
):
    """Kalman filter (filterpy) over snapshot fixes.

    ``z_m``: [T] (one receiver), [T, K] (rigid train: column k measures x - ``offsets_m[k]``)
    or [T, K, C] (C candidate fixes per receiver, e.g. the two sides of a cable feed: the
    one nearest the prediction is used, nearest-neighbour association).  ``r_m2``: scalar,
    [T] or [T, K] measurement variances.  NaN measurements are skipped (prediction only);
    with ``gate_sigma`` a measurement whose innovation exceeds that many standard
    deviations is rejected (the covariance grows until the filter re-acquires).
    ``start_at_first``: (x0, p0) is the state at the first epoch, made from that epoch's
    measurement (e.g. the first snapshot fix with its variance), which is therefore not used
    again (no double counting); otherwise the prior precedes the first epoch.
    Returns (x [T], v [T], var_x [T], nis [T]).

    Parameters
    ----------
    z_m : numpy.ndarray
        Snapshot fixes [m]: [T], [T, K] or [T, K, C] (see above); NaN: no measurement.
    r_m2 : float or numpy.ndarray
        Measurement variances [m^2]: scalar, [T] or [T, K]; positive.
    dt_s : float
        Time between epochs [s]; positive.
    accel_sigma : float
        Standard deviation of the white acceleration noise [m/s^2]; positive.
    x0 : tuple of float
        Initial state: position [m] and speed [m/s].
    p0 : tuple of float
        Initial variances of position [m^2] and speed [m^2/s^2].
    offsets_m : numpy.ndarray or None
        Distance of each measurement column behind the tracked position [m], [K]; None: zeros.
    gate_sigma : float or None
        Innovation gate in standard deviations [1]; None: no gate.
    start_at_first : bool
        (x0, p0) is the state at the first epoch (see above).

    Returns
    -------
    tuple of numpy.ndarray
        ``(x, v, var_x, nis)``, each [T]: filtered position [m], speed [m/s], position
        variance [m^2], and the normalized innovation squared per measurement [1] (NaN at
        epochs without an update of all K measurements).

    Raises
    ------
    ValueError
        When ``z_m`` is not 1-, 2- or 3-D, ``offsets_m`` has not K entries, ``r_m2`` has
        another shape or is not positive, or ``dt_s`` or ``accel_sigma`` is not positive.
    """
    z = _as_candidates(z_m)
    n, k, _ = z.shape
    offs = np.zeros(k) if offsets_m is None else np.asarray(offsets_m, dtype=float)
    if offs.shape != (k,):
        raise ValueError("offsets_m must have one entry per measurement column")
    r_arr = np.asarray(r_m2, dtype=float)
    r = (
        np.full((n, k), float(r_arr))
        if r_arr.ndim == 0
        else np.repeat(r_arr[:, None], k, axis=1)
        if r_arr.ndim == 1
        else r_arr
    )
    if r.shape != (n, k):
        raise ValueError(f"r_m2 must be a scalar, [T] or [T, K]; got shape {r_arr.shape}")
    if np.any(r <= 0):
        raise ValueError("r_m2 must be positive")
    kf = KalmanFilter(dim_x=2, dim_z=k)
    kf.F, kf.Q = _cv_model(dt_s, accel_sigma)
    kf.H = np.column_stack([np.ones(k), np.zeros(k)])
    kf.x = np.array([[x0[0]], [x0[1]]])
    kf.P = np.diag([p0[0], p0[1]])
    out = np.empty((n, 3))
    nis = np.full(n, np.nan)
    for t in range(n):
        if t == 0 and start_at_first:
            out[t] = kf.x[0, 0], kf.x[1, 0], kf.P[0, 0]
            continue
        kf.predict()
        pred = kf.x[0, 0] - offs
        cand = z[t]
        j = np.nanargmin(np.where(np.isfinite(cand), np.abs(cand - pred[:, None]), np.inf), axis=1)
        zt = cand[np.arange(k), j] + offs
        if gate_sigma is not None:
            s_inn = kf.P[0, 0] + r[t]
            zt = np.where(np.abs(zt - kf.x[0, 0]) <= gate_sigma * np.sqrt(s_inn), zt, np.nan)
        use = np.isfinite(zt)
        if np.all(use):
            kf.update(zt.reshape(-1, 1), R=np.diag(r[t]))
            nis[t] = float((kf.y.T @ kf.SI @ kf.y).item()) / k
        elif np.any(use):  # rigid train: update with the receivers that passed the gate
            h_sub = kf.H[use]
            kf.update(zt[use].reshape(-1, 1), R=np.diag(r[t][use]), H=h_sub)
        out[t] = kf.x[0, 0], kf.x[1, 0], kf.P[0, 0]
    return out[:, 0], out[:, 1], out[:, 2], nis


def kf_track_batch(
    z_m: np.ndarray,
    r_m2: np.ndarray,
    dt_s: float,
    accel_sigma: float,
    x0_m: np.ndarray,
    p0: tuple[float, float],
    gate_sigma: float | None = 4.0,
    start_at_first: bool = False,
) -> np.ndarray:
    """The single-receiver :func:`kf_track` (initial speed 0, one candidate per epoch) for B
    independent tracks at once, vectorized over the batch: ``z_m``, ``r_m2`` [T, B],
    ``x0_m`` [B].  Same model, same gate, same NaN handling; covariance update in the
    standard form (filterpy uses Joseph's, equal for the optimal gain; the test checks the
    two agree); ``p0`` = (position variance, scalar or [B], speed variance).  Used for the
    Monte Carlo realizations and the sensitivity sweeps.
    Returns the position estimates [T, B].

    Parameters
    ----------
    z_m : numpy.ndarray
        Snapshot fixes [m], [T, B]; NaN: no measurement.
    r_m2 : numpy.ndarray
        Measurement variances [m^2], broadcastable to [T, B]; positive.
    dt_s : float
        Time between epochs [s]; positive.
    accel_sigma : float
        Standard deviation of the white acceleration noise [m/s^2]; positive.
    x0_m : numpy.ndarray
        Initial positions [m], [B] (or a scalar).
    p0 : tuple
        Initial variances: position [m^2] (scalar or [B]) and speed [m^2/s^2] (scalar).
    gate_sigma : float or None
        Innovation gate in standard deviations [1]; None: no gate.
    start_at_first : bool
        (x0_m, p0) is the state at the first epoch (as in :func:`kf_track`).

    Returns
    -------
    numpy.ndarray
        Filtered positions [T, B] [m].

    Raises
    ------
    ValueError
        When ``z_m`` is not 2-D, or ``r_m2``, ``dt_s`` or ``accel_sigma`` is not positive.
    """
    z = np.asarray(z_m, dtype=float)
    if z.ndim != 2:
        raise ValueError("z_m must be [T, B]")
    r = np.broadcast_to(np.asarray(r_m2, dtype=float), z.shape)
    if np.any(r <= 0):
        raise ValueError("r_m2 must be positive")
    f, q = _cv_model(dt_s, accel_sigma)
    dt = f[0, 1]
    n, b = z.shape
    x = np.array(np.broadcast_to(np.asarray(x0_m, dtype=float), (b,)))
    v = np.zeros(b)
    p00 = np.array(np.broadcast_to(np.asarray(p0[0], dtype=float), (b,)))
    p01, p11 = np.zeros(b), np.full(b, float(p0[1]))
    out = np.empty((n, b))
    for t in range(n):
        if t == 0 and start_at_first:
            out[t] = x
            continue
        x = x + dt * v
        p00, p01, p11 = (p00 + 2.0 * dt * p01 + dt * dt * p11 + q[0, 0], p01 + dt * p11 + q[0, 1], p11 + q[1, 1])
        s = p00 + r[t]
        y = z[t] - x
        use = np.isfinite(y)
        if gate_sigma is not None:
            use &= np.abs(np.where(use, y, 0.0)) <= gate_sigma * np.sqrt(s)
        k0 = np.where(use, p00 / s, 0.0)
        k1 = np.where(use, p01 / s, 0.0)
        y = np.where(use, y, 0.0)
        x, v = x + k0 * y, v + k1 * y
        p00, p01, p11 = p00 - k0 * p00, p01 - k0 * p01, p11 - k1 * p01
        out[t] = x
    return out


def pf_track(
    z_m: np.ndarray,
    r_m2,
    dt_s: float,
    accel_sigma: float,
    x0: tuple[float, float],
    p0: tuple[float, float],
    n_particles: int,
    rng: np.random.Generator,
    outlier_prob: float = 0.02,
    outlier_width_m: float = 200.0,
    inject_frac: float = 0.01,
    start_at_first: bool = False,
):
    """Bootstrap particle filter with systematic resampling (:func:`systematic_resample_with`).

    ``z_m`` [T] or [T, C] candidate fixes; likelihood: the sum over candidates of
    N(z; x, R), mixed with a uniform outlier density of weight ``outlier_prob`` over
    ``outlier_width_m`` (robust to a wrong fix).  Resampling when the effective sample
    size drops below N/2, followed by a Gaussian-kernel regularization (Silverman's
    bandwidth) against sample impoverishment; after every update a fraction ``inject_frac`` of the particles
    is redrawn around the candidate nearest the estimate (sensor resetting, so a filter
    that lost the train can find it again).  ``start_at_first`` as in :func:`kf_track`.
    Returns (x [T], var_x [T]).

    Parameters
    ----------
    z_m : numpy.ndarray
        Candidate fixes [m], [T] or [T, C]; NaN: no candidate.
    r_m2 : float or numpy.ndarray
        Measurement variance [m^2], scalar or [T].
    dt_s : float
        Time between epochs [s]; positive.
    accel_sigma : float
        Standard deviation of the white acceleration noise [m/s^2]; positive.
    x0 : tuple of float
        Mean of the initial particles: position [m] and speed [m/s].
    p0 : tuple of float
        Variances of the initial particles: position [m^2] and speed [m^2/s^2].
    n_particles : int
        Number N of particles; >= 10.
    rng : numpy.random.Generator
        Random stream of the filter.
    outlier_prob : float
        Weight of the uniform outlier density in the likelihood [1].
    outlier_width_m : float
        Width of the uniform outlier density [m].
    inject_frac : float
        Share of the particles redrawn around the nearest candidate after every update [1].
    start_at_first : bool
        (x0, p0) is the state at the first epoch (as in :func:`kf_track`).

    Returns
    -------
    tuple of numpy.ndarray
        ``(x, var_x)``, each [T]: the weighted mean position [m] and its weighted variance
        [m^2].

    Raises
    ------
    ValueError
        When ``n_particles`` < 10, or ``dt_s`` or ``accel_sigma`` is not positive.
    """
    if n_particles < 10:
        raise ValueError("n_particles must be >= 10")
    z = np.asarray(z_m, dtype=float)
    z = z[:, None] if z.ndim == 1 else z
    r = np.broadcast_to(np.asarray(r_m2, dtype=float), (z.shape[0],))
    f, q = _cv_model(dt_s, accel_sigma)
    lq = np.linalg.cholesky(q + 1e-12 * np.eye(2))
    parts = np.column_stack(
        [
            x0[0] + np.sqrt(p0[0]) * rng.standard_normal(n_particles),
            x0[1] + np.sqrt(p0[1]) * rng.standard_normal(n_particles),
        ]
    )
    w = np.full(n_particles, 1.0 / n_particles)
    out = np.empty((z.shape[0], 2))
    n_inj = int(round(inject_frac * n_particles))
    bandwidth = (4.0 / (4.0 * n_particles)) ** (1.0 / 6.0)  # Silverman, 2-D state
    for t in range(z.shape[0]):
        if t == 0 and start_at_first:
            mean = np.sum(w * parts[:, 0])
            out[t] = mean, np.sum(w * (parts[:, 0] - mean) ** 2)
            continue
        parts = parts @ f.T + rng.standard_normal((n_particles, 2)) @ lq.T
        zt = z[t][np.isfinite(z[t])]
        if zt.size:
            g = np.exp(-0.5 * (zt[None, :] - parts[:, :1]) ** 2 / r[t]).sum(axis=1)
            lik = (1.0 - outlier_prob) * g / np.sqrt(2.0 * np.pi * r[t]) + outlier_prob / outlier_width_m
            w = w * lik
            w /= w.sum()
            if 1.0 / np.sum(w * w) < n_particles / 2:
                mean_p = w @ parts
                std_p = np.sqrt(np.maximum(w @ (parts - mean_p) ** 2, 1e-12))
                idx = systematic_resample_with(w, rng)
                parts, w = parts[idx], np.full(n_particles, 1.0 / n_particles)
                # regularization (Gaussian kernel, Silverman's bandwidth) against impoverishment
                parts = parts + bandwidth * std_p * rng.standard_normal(parts.shape)
            if n_inj:
                mean = np.sum(w * parts[:, 0])
                c = zt[np.argmin(np.abs(zt - mean))]
                sel = rng.choice(n_particles, n_inj, replace=False)
                parts[sel, 0] = c + np.sqrt(r[t]) * rng.standard_normal(n_inj)
                parts[sel, 1] = np.sum(w * parts[:, 1])
                w[sel] = np.mean(w)
                w /= w.sum()
        mean = np.sum(w * parts[:, 0])
        out[t] = mean, np.sum(w * (parts[:, 0] - mean) ** 2)
    return out[:, 0], out[:, 1]


def systematic_resample_with(weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Systematic resampling (Kitagawa 1996) with its one random offset drawn from ``rng``:
    particle i is copied for every point (u + j) / N, j = 0 .. N-1, that falls in its
    interval of the cumulative weights.  The same algorithm as filterpy's
    ``systematic_resample`` (which draws from numpy's global state; the test checks the
    two agree for the same offset), thread-safe and reproducible.

    Parameters
    ----------
    weights : numpy.ndarray
        Particle weights [N] (normalized here); finite and non-negative.
    rng : numpy.random.Generator
        Source of the one offset u in [0, 1).

    Returns
    -------
    numpy.ndarray
        Indices of the particles to copy [N] (non-decreasing integers).

    Raises
    ------
    ValueError
        When ``weights`` is not a non-empty 1-D array of finite non-negative numbers.
    """
    w = np.asarray(weights, dtype=float)
    if w.ndim != 1 or w.size == 0 or np.any(w < 0) or not np.isfinite(w).all():
        raise ValueError("weights must be a non-empty 1-D array of finite non-negative numbers")
    n = w.size
    points = (float(rng.random()) + np.arange(n)) / n
    cum = np.cumsum(w / w.sum())
    cum[-1] = 1.0
    return np.minimum(np.searchsorted(cum, points, side="right"), n - 1)


def robust_variance(errors_m: np.ndarray) -> float:
    """(1.4826 MAD)^2 of the errors: the measurement variance from a calibration run.

    Parameters
    ----------
    errors_m : numpy.ndarray
        Errors [m], any shape; non-finite values are ignored.

    Returns
    -------
    float
        Robust variance [m^2]; at least 1e-6 (the scaled MAD is floored at 1e-3 m).

    Raises
    ------
    ValueError
        When fewer than two errors are finite.
    """
    e = np.asarray(errors_m, dtype=float)
    e = e[np.isfinite(e)]
    if e.size < 2:
        raise ValueError("need at least two finite errors")
    mad = 1.4826 * median_abs_deviation(e, axis=None)  # 1.4826: the normal consistency constant to 4 digits
    return float(max(mad, 1e-3) ** 2)
