"""Fixed-interval Rauch–Tung–Striebel smoother (offline) over a Kalman/EKF track with a
linear transition (Rauch, Tung & Striebel 1965; Särkkä 2013, Theorem 8.2):

    P⁻_{k+1} = F P_k Fᵀ + Q,         C_k = P_k Fᵀ (P⁻_{k+1})⁻¹,
    xˢ_k = x_k + C_k (xˢ_{k+1} − F x_k),  Pˢ_k = P_k + C_k (Pˢ_{k+1} − P⁻_{k+1}) C_kᵀ.

The EKF's prediction is exactly x⁻_{k+1} = F x_k, P⁻_{k+1} = F P_k Fᵀ + Q (the measurement
model's nonlinearity enters only through the filtered x_k, P_k), so the stored posteriors
are enough. A re-acquisition reset at epoch k is part of the posterior at k.

Why not filterpy's ``KalmanFilter.rts_smoother`` (a dependency already): it takes no epochs
before the first fix (the track's leading NaN states) and forms the gain with an explicit
inverse of P⁻; here the gain solves P⁻ Cᵀ = F P. The two agree to rounding
(``tests/nr/test_smoother.py``), so the published RTS numbers stay as computed here.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def rts_smooth(states: NDArray, covs: NDArray, f: NDArray, q: NDArray) -> tuple[NDArray, NDArray]:
    """Smoothed states [n, d] and covariances [n, d, d] from the filtered ones.

    Leading epochs with a NaN state (no track yet) stay NaN; the rest must be finite.

    Parameters
    ----------
    states : numpy.ndarray
        [n, d] filtered states (e.g. [x, y, vx, vy, ax, ay] in m, m/s, m/s²); NaN rows first
        for the epochs before the track starts.
    covs : numpy.ndarray
        [n, d, d] their filtered covariances (the states' units squared).
    f : numpy.ndarray
        [d, d] transition matrix F of one epoch interval.
    q : numpy.ndarray
        [d, d] process noise covariance Q of one epoch interval.

    Returns
    -------
    tuple of numpy.ndarray
        ``(x_s, p_s)``: smoothed states [n, d] and covariances [n, d, d], in the units of
        ``states`` and ``covs`` (the leading NaN epochs copied unchanged).

    Raises
    ------
    ValueError
        When ``states`` is not [n, d] or ``covs`` not [n, d, d], ``f`` or ``q`` is not
        [d, d], or a state after the first finite one is not finite.
    """
    xs = np.asarray(states, float)
    ps = np.asarray(covs, float)
    f = np.asarray(f, float)
    q = np.asarray(q, float)
    if xs.ndim != 2 or ps.shape != xs.shape + (xs.shape[1],):
        raise ValueError(f"states must be [n, d] and covs [n, d, d], got {xs.shape} and {ps.shape}")
    d = xs.shape[1]
    if f.shape != (d, d) or q.shape != (d, d):
        raise ValueError(f"f and q must be [{d}, {d}], got {f.shape} and {q.shape}")
    finite = np.all(np.isfinite(xs), axis=1)
    k0 = int(np.argmax(finite)) if finite.any() else xs.shape[0]
    if not finite[k0:].all():
        raise ValueError("states must be finite after the first finite epoch")
    x_s = xs.copy()
    p_s = ps.copy()
    for k in range(xs.shape[0] - 2, k0 - 1, -1):
        p_pred = f @ ps[k] @ f.T + q
        c = np.linalg.solve(p_pred, f @ ps[k]).T  # P_k Fᵀ (P⁻)⁻¹ (P⁻ symmetric)
        x_s[k] = xs[k] + c @ (x_s[k + 1] - f @ xs[k])
        p_s[k] = ps[k] + c @ (p_s[k + 1] - p_pred) @ c.T
    return x_s, p_s
