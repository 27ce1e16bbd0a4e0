"""Snapshot position fix of the train: weighted Gauss–Newton least squares of one epoch's
AOD/TOA measurements (the measurement model of :mod:`railradio.nr.tracking.measurement`), without
tracking; the tracker's start, its re-acquisition and a baseline [ours]."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from railradio.nr.channel.antenna import wrap_rad
from railradio.nr.tracking.measurement import MEASUREMENT_SETS, jac_terms

if TYPE_CHECKING:  # annotations only
    from railradio.nr.tracking.ekf import TrackerConfig


def snapshot_ls(
    rrh_xy: NDArray, aod: NDArray, toa: NDArray, dh_m: float, cfg: TrackerConfig, x_init: NDArray, n_iter: int = 20
) -> tuple[NDArray, NDArray]:
    """Weighted Gauss–Newton position fix [x, y] from one epoch and its covariance [m²]
    (:func:`snapshot_ls_batch` for one epoch).

    Parameters
    ----------
    rrh_xy : numpy.ndarray
        [m, 2] positions (x, y) of the measured RRHs [m].
    aod, toa : numpy.ndarray
        [m] their measured AODs [rad] and TOAs [s] (only those of ``cfg.measurements`` are used).
    dh_m : float
        Height difference between the RRHs and the train antenna [m].
    cfg : TrackerConfig
        Measurement set and measurement noise W (the weights).
    x_init : numpy.ndarray
        [2] initial guess (x, y) [m].
    n_iter : int
        Most Gauss–Newton iterations.

    Returns
    -------
    tuple of numpy.ndarray
        ``(fix, cov)``: the position (x, y) [2] [m] and its covariance pinv(JᵀWJ) [2, 2] [m²].

    Raises
    ------
    ValueError
        When no RRH position in ``rrh_xy`` is finite.
    """
    rrh_xy = np.asarray(rrh_xy, float).reshape(-1, 2)
    p, cov = snapshot_ls_batch(
        rrh_xy[None],
        np.asarray(aod, float).reshape(1, -1),
        np.asarray(toa, float).reshape(1, -1),
        dh_m,
        cfg,
        np.asarray(x_init, float).reshape(1, 2),
        n_iter,
        with_cov=True,
    )
    return p[0], cov[0]


def snapshot_ls_batch(
    rrh_xy: NDArray,
    aod: NDArray,
    toa: NDArray,
    dh_m: float,
    cfg: TrackerConfig,
    x_init: NDArray,
    n_iter: int = 20,
    with_cov: bool = False,
) -> tuple[NDArray, NDArray | None]:
    """Weighted Gauss–Newton position fixes of independent epochs, all at once.

    ``rrh_xy`` [E, m, 2], ``aod``/``toa`` [E, m] (NaN RRH positions pad epochs with fewer
    measurements; every epoch needs at least one), ``x_init`` [E, 2]. Each epoch iterates
    p ← p + (JᵀWJ)⁻¹ JᵀW (z - h(p)) (angle residuals wrapped) until its step is under 1 µm,
    at most ``n_iter`` times, and stops early where det JᵀWJ = 0; W is the inverse of
    :meth:`TrackerConfig.noise` at the initial guess. Returns the fixes [E, 2] and, with
    ``with_cov``, the covariances pinv(JᵀWJ) at the fixes [E, 2, 2] [m²].

    Parameters
    ----------
    rrh_xy : numpy.ndarray
        [E, m, 2] positions (x, y) of each epoch's measured RRHs [m]; NaN rows: padding.
    aod, toa : numpy.ndarray
        [E, m] measured AODs [rad] and TOAs [s] (only those of ``cfg.measurements`` are used).
    dh_m : float
        Height difference between the RRHs and the train antenna [m].
    cfg : TrackerConfig
        Measurement set and measurement noise W (:meth:`TrackerConfig.variances`).
    x_init : numpy.ndarray
        [E, 2] initial guesses (x, y) [m].
    n_iter : int
        Most Gauss–Newton iterations per epoch.
    with_cov : bool
        Also return the covariances.

    Returns
    -------
    tuple
        ``(fixes, covs)``: positions (x, y) [E, 2] [m] and, with ``with_cov``, covariances
        [E, 2, 2] [m²], else None.

    Raises
    ------
    ValueError
        When an epoch has no finite RRH position in ``rrh_xy``.
    """
    xy = np.asarray(rrh_xy, float)
    valid = np.isfinite(xy[..., 0])  # [E, m]
    if not valid.any(axis=1).all():
        raise ValueError("rrh_xy: every epoch needs at least one measured RRH")
    xy = np.where(valid[..., None], xy, 0.0)
    use_aod, use_toa = MEASUREMENT_SETS[cfg.measurements]
    n_e = valid.shape[0]
    p = np.asarray(x_init, float).copy()
    # weights [E, m, per] at the initial guess (0 for padding)
    dx0, dy0 = p[:, :1] - xy[..., 0], p[:, 1:] - xy[..., 1]
    var = cfg.predict(dx0, dy0, dh_m)[1]  # at the initial guess (the AOD model's σ at its azimuth)
    w = np.where(valid[..., None], 1.0 / var, 0.0)
    z = np.stack(([np.asarray(aod, float)] if use_aod else []) + ([np.asarray(toa, float)] if use_toa else []), axis=-1)
    z = np.where(valid[..., None], z, 0.0)

    def lin(idx):
        """J [e, m, per, 2] and wrapped residuals [e, m, per] of the epochs ``idx`` at p."""
        ok = valid[idx]
        dx = np.where(ok, p[idx, :1] - xy[idx, :, 0], 1.0)
        dy = np.where(ok, p[idx, 1:] - xy[idx, :, 1], 1.0)
        jac = jac_terms(dx, dy, dh_m, cfg.measurements)
        h = cfg.predict(dx, dy, dh_m)[0]  # with the AOD model's bias
        r = z[idx] - h
        if use_aod:
            r[..., 0] = wrap_rad(r[..., 0])
        return jac, np.where(ok[..., None], r, 0.0)

    def normal(idx, jac, r=None):
        info = np.einsum("empi,emp,empj->eij", jac, w[idx], jac)
        return info, (None if r is None else np.einsum("empi,emp,emp->ei", jac, w[idx], r))

    active = np.ones(n_e, dtype=bool)
    for _ in range(n_iter):
        if not active.any():
            break
        idx = np.flatnonzero(active)
        jac, r = lin(idx)
        info, g = normal(idx, jac, r)
        # 2 × 2 solve in closed form; a singular JᵀWJ stops that epoch
        det = info[:, 0, 0] * info[:, 1, 1] - info[:, 0, 1] * info[:, 1, 0]
        ok = det != 0
        det = np.where(ok, det, 1.0)
        step = (
            np.stack(
                [info[:, 1, 1] * g[:, 0] - info[:, 0, 1] * g[:, 1], info[:, 0, 0] * g[:, 1] - info[:, 1, 0] * g[:, 0]],
                axis=1,
            )
            / det[:, None]
        )
        p[idx[ok]] += step[ok]
        done = ~ok | (np.linalg.norm(step, axis=1) < 1e-6)
        active[idx[done]] = False
    if not with_cov:
        return p, None
    idx = np.arange(n_e)
    jac, _ = lin(idx)
    return p, np.linalg.pinv(normal(idx, jac)[0])
