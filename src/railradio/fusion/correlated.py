"""Correlated TDOA errors: two range differences that share the serving BS (docs/model/fusion.md §5).

Source 002 has one TDOA, t_{2,1}, and one AOA, with independent errors.  A
receiver usually has more than one neighbour: here BS0 at (-D, d) joins BS1 (0, d) and
BS2 (D, d), both TDOAs referenced to the serving BS1,

    Δ2 = r2 - r1 + n2,   Δ0 = r0 - r1 + n0,   (n2, n0) ~ N(0, σ_Δ² [[1, ρ], [ρ, 1]]),

and the bearing θ at BS1 as before.  Where the correlation comes from: if every BS's time of
arrival has an independent error, σ_1 at the reference BS1 and σ_o at the others, then
n2 = e2 - e1 and n0 = e0 - e1 share -e1 and ρ = σ_1² / (σ_1² + σ_o²) — 0.5 for equal
errors, towards 1 when the reference's synchronization error dominates
(:func:`common_reference_rho`).  The sweep holds each TDOA's own σ_Δ at the source's value
and varies ρ.

Each TDOA is turned into a position on the track like the source's (BS0's by mirroring
x → -x), giving x_T2 and x_T0, which the source's linear fusion would weight by their
inverse variances as if independent (``naive``).  Their errors are correlated:
x_Ti - x ≈ n_i / g_i with g_i = d(r_i - r1)/dx, so cov(x_T2, x_T0) ≈ ρ σ_Δ²/(g2 g0) —
*negative* for ρ > 0 here, because g2 < 0 < g0 on the train's interval.  The ``whitened``
fusion is the generalized least-squares (BLUE) combination with that covariance; at ρ = 0
it is the naive weighting exactly, and with one TDOA it is the source's eq. 9–10.

Cramér–Rao bound on x with the correlated covariance (a 3-measurement Gaussian model):

    J(x) = (g2² - 2ρ g2 g0 + g0²) / (σ_Δ² (1 - ρ²)) + (d / r1²)² / σ_θ².

At ρ → 1 the difference Δ2 - Δ0 = r2 - r0 becomes error-free and J → ∞: a correlation the
receiver knows is information, not only a nuisance.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from railradio.fusion.estimators import tdoa_on_track
from railradio.fusion.geometry import CellGeometry


def _check_rho(rho: float) -> float:
    rho = float(rho)
    if not (-1.0 < rho < 1.0):
        raise ValueError(f"rho must be in (-1, 1), got {rho!r}")
    return rho


def common_reference_rho(sigma_ref_s: float, sigma_other_s: float) -> tuple[float, float]:
    """(ρ, σ_TDOA [s]) of two TDOAs that share a reference BS with TOA error σ_ref while the
    other two BSs have independent TOA errors σ_other: ρ = σ_ref²/(σ_ref² + σ_other²),
    σ_TDOA = sqrt(σ_ref² + σ_other²).

    Parameters
    ----------
    sigma_ref_s : float
        Standard deviation σ_ref of the time-of-arrival error at the shared reference BS [s],
        finite, >= 0.
    sigma_other_s : float
        Standard deviation σ_other of the time-of-arrival error at each of the two other BSs
        [s], finite, >= 0.

    Returns
    -------
    rho : float
        Correlation coefficient ρ of the two TDOA errors [1], in [0, 1].
    sigma_tdoa_s : float
        Standard deviation σ_TDOA of each of the two TDOAs [s].

    Raises
    ------
    ValueError
        If ``sigma_ref_s`` or ``sigma_other_s`` is not a finite number >= 0, or both are 0.
    """
    for name, v in (("sigma_ref_s", sigma_ref_s), ("sigma_other_s", sigma_other_s)):
        if not (v >= 0 and math.isfinite(v)):
            raise ValueError(f"{name} must be a finite number >= 0 [s], got {v!r}")
    var = sigma_ref_s**2 + sigma_other_s**2
    if var == 0:
        raise ValueError("sigma_ref_s and sigma_other_s cannot both be 0")
    return sigma_ref_s**2 / var, math.sqrt(var)


def correlated_pair(z_a: ArrayLike, z_b: ArrayLike, rho: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Two unit-variance normals with correlation ρ from two independent ones (Cholesky):
    (z_a, ρ z_a + sqrt(1 - ρ²) z_b).  The first is z_a itself, so a sweep over ρ keeps the
    first TDOA's errors (common random numbers).

    Parameters
    ----------
    z_a : array_like of float
        Standard normal draws [1], any shape.
    z_b : array_like of float
        Standard normal draws independent of ``z_a`` [1], broadcastable with ``z_a``.
    rho : float
        The wanted correlation coefficient ρ [1], in (-1, 1).

    Returns
    -------
    n_a : numpy.ndarray of float
        ``z_a`` itself (as float) [1], the shape of ``z_a``.
    n_b : numpy.ndarray of float
        ρ z_a + sqrt(1 - ρ²) z_b [1], the broadcast shape of ``z_a`` and ``z_b``: standard
        normal, with correlation ρ to ``n_a``.

    Raises
    ------
    ValueError
        If ``rho`` is not in (-1, 1).
    """
    rho = _check_rho(rho)
    z_a = np.asarray(z_a, dtype=float)
    return z_a, rho * z_a + math.sqrt(1.0 - rho * rho) * np.asarray(z_b, dtype=float)


# --- the third BS: BS0 at (-D, d), the mirror image of BS2 -----------------------------
def range_difference0_m(x_m: ArrayLike, geom: CellGeometry) -> NDArray[np.float64]:
    """r0 - r1 [m] with BS0 at (-D, d): (r2 - r1)(-x).

    Parameters
    ----------
    x_m : array_like of float
        Train position(s) (x, 0) along the track [m], any shape.
    geom : CellGeometry
        The cell geometry of BS1 and BS2 (BS0 is BS2 mirrored about x = 0).

    Returns
    -------
    numpy.ndarray of float
        Range difference r0 - r1 between BS0 and the serving BS1 [m], the shape of ``x_m``.
    """
    return geom.range_difference_m(-np.asarray(x_m, dtype=float))


def range_difference0_slope(x_m: ArrayLike, geom: CellGeometry) -> NDArray[np.float64]:
    """g0(x) = d(r0 - r1)/dx = -g(-x) [m/m], positive on the train's interval.

    Parameters
    ----------
    x_m : array_like of float
        Train position(s) (x, 0) along the track [m], any shape.
    geom : CellGeometry
        The cell geometry of BS1 and BS2 (BS0 is BS2 mirrored about x = 0).

    Returns
    -------
    numpy.ndarray of float
        The slope g0(x) of the range difference r0 - r1 [m/m], the shape of ``x_m``.
    """
    return -geom.range_difference_slope(-np.asarray(x_m, dtype=float))


def tdoa0_on_track(delta0_m: ArrayLike, geom: CellGeometry) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Position on the track from Δ0 = r0 - r1: the source's closed form, mirrored.

    Parameters
    ----------
    delta0_m : array_like of float
        Measured range difference Δ0 = r0 - r1 between BS0 and BS1 [m], any shape.
    geom : CellGeometry
        The cell geometry of BS1 and BS2 (BS0 is BS2 mirrored about x = 0).

    Returns
    -------
    x_m : numpy.ndarray of float
        Position on the track [m], the shape of ``delta0_m``; ±inf where there is no
        solution (|Δ0| >= D), to be clipped by :func:`railradio.fusion.clip_to_segment`.
    no_solution : numpy.ndarray of bool
        Boolean mask of |Δ0| >= D, the shape of ``delta0_m``.
    """
    x, no_solution = tdoa_on_track(delta0_m, geom)
    return -x, no_solution


# --- fusion --------------------------------------------------------------------------
def fuse_two_tdoa_aoa(
    x_t2: ArrayLike, sd_t2: ArrayLike, x_t0: ArrayLike, sd_t0: ArrayLike, x_a: ArrayLike, var_a: ArrayLike, rho: float
) -> NDArray[np.float64]:
    """BLUE of x from two TDOA positions and one AOA position.

    ``sd_t2``, ``sd_t0`` are the TDOA positions' *signed* standard deviations σ_Δ/g_i [m]
    (the sign carries the sign of their error correlation: cov = ρ·sd_t2·sd_t0); ``var_a``
    the AOA position's variance [m²], independent of both.  With C the 2×2 covariance of
    (x_T2, x_T0), the weights are C⁻¹1 and 1/var_a, normalized:

        u2 = (v0 - c)/det, u0 = (v2 - c)/det, det = v2 v0 - c², c = ρ sd_t2 sd_t0.

    ρ = 0 gives the inverse-variance weighting of three independent estimates (the source's
    eq. 9–10 with one more term).  ``sd_t0 = inf`` with ρ = 0 drops the second TDOA: the
    source's two-estimate fusion exactly.  (With ρ ≠ 0 an infinitely noisy second TDOA
    still reveals part of the first one's error, and its limit weight is 1/((1-ρ²)v2).)

    All array arguments must broadcast together.

    Parameters
    ----------
    x_t2 : array_like of float
        Position from the TDOA Δ2 = r2 - r1 (:func:`railradio.fusion.tdoa_on_track`) [m].
    sd_t2 : array_like of float
        Signed standard deviation σ_Δ/g2 of ``x_t2`` [m], nonzero.
    x_t0 : array_like of float
        Position from the TDOA Δ0 = r0 - r1 (:func:`tdoa0_on_track`) [m]; ignored where
        ``sd_t0`` is infinite.
    sd_t0 : array_like of float
        Signed standard deviation σ_Δ/g0 of ``x_t0`` [m], nonzero; inf drops the second TDOA.
    x_a : array_like of float
        Position from the AOA (:func:`railradio.fusion.aoa_on_track`) [m].
    var_a : array_like of float
        Variance of ``x_a`` [m²], > 0.
    rho : float
        Correlation coefficient ρ of the two TDOA errors [1], in (-1, 1).

    Returns
    -------
    numpy.ndarray of float
        The fused position [m], the broadcast shape of the array arguments.

    Raises
    ------
    ValueError
        If ``rho`` is not in (-1, 1), a value of ``sd_t2`` or ``sd_t0`` is zero or NaN, or a
        value of ``var_a`` is not > 0.
    """
    rho = _check_rho(rho)
    sd_t2, sd_t0 = np.asarray(sd_t2, dtype=float), np.asarray(sd_t0, dtype=float)
    var_a = np.asarray(var_a, dtype=float)
    for name, v in (("sd_t2", sd_t2), ("sd_t0", sd_t0)):
        if np.any(~(np.abs(v) > 0)):
            raise ValueError(f"{name} must be nonzero [m]")
    if np.any(~(var_a > 0)):
        raise ValueError("var_a must be > 0 [m²]")
    # written with the inverse standard deviations so that sd = inf drops an estimate
    a2, a0 = 1.0 / sd_t2, 1.0 / sd_t0
    scale = 1.0 / (1.0 - rho * rho)
    u2 = scale * (a2 * a2 - rho * a2 * a0)
    u0 = scale * (a0 * a0 - rho * a2 * a0)
    ua = 1.0 / var_a
    return (u2 * np.asarray(x_t2) + u0 * np.where(np.isinf(sd_t0), 0.0, np.asarray(x_t0)) + ua * np.asarray(x_a)) / (
        u2 + u0 + ua
    )


def fisher_information_correlated(
    x_m: ArrayLike, sigma_delta_m: float, sigma_theta_rad: float, rho: float, geom: CellGeometry
) -> NDArray[np.float64]:
    """J(x) [1/m²] of (Δ2, Δ0, θ) with TDOA correlation ρ (module docstring).

    Parameters
    ----------
    x_m : array_like of float
        Train position(s) x on the track [m], any shape.
    sigma_delta_m : float
        Standard deviation σ_Δ of each range-difference error, c·σ_TDOA [m], finite, > 0.
    sigma_theta_rad : float
        Standard deviation σ_θ of the AOA error at BS1 [rad], finite, > 0.
    rho : float
        Correlation coefficient ρ of the two TDOA errors [1], in (-1, 1).
    geom : CellGeometry
        The cell geometry of BS1 and BS2 (BS0 is BS2 mirrored about x = 0).

    Returns
    -------
    numpy.ndarray of float
        Fisher information J(x) about the track position [1/m²], the shape of ``x_m``.

    Raises
    ------
    ValueError
        If ``rho`` is not in (-1, 1), or ``sigma_delta_m`` or ``sigma_theta_rad`` is not a
        finite number > 0.
    """
    rho = _check_rho(rho)
    if not (sigma_delta_m > 0 and math.isfinite(sigma_delta_m)):
        raise ValueError(f"sigma_delta_m must be a finite number > 0, got {sigma_delta_m!r}")
    if not (sigma_theta_rad > 0 and math.isfinite(sigma_theta_rad)):
        raise ValueError(f"sigma_theta_rad must be a finite number > 0, got {sigma_theta_rad!r}")
    g2 = geom.range_difference_slope(x_m)
    g0 = range_difference0_slope(x_m, geom)
    j_tdoa = (g2 * g2 - 2.0 * rho * g2 * g0 + g0 * g0) / (sigma_delta_m**2 * (1.0 - rho * rho))
    return j_tdoa + geom.aoa_slope(x_m) ** 2 / sigma_theta_rad**2
