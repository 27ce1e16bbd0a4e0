"""Position on the track from a TDOA or an AOA, and their inverse-variance fusion.

Source 002, §2: TDOA ∩ track (eq. 3–5), AOA ∩ track (eq. 7), linear fusion (eq. 9–10).
All functions are vectorized over arbitrary array shapes.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq

from railradio.fusion.geometry import CellGeometry


def tdoa_on_track(delta_m: ArrayLike, geom: CellGeometry) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Closed-form intersection of the TDOA hyperbola with the track y = 0.

    With BS1 at (0, d), BS2 at (D, d) and Δ = r2 - r1 the measured range difference,
    squaring r2 = Δ + r1 twice gives (D² - Δ²)·(4x² - 4Dx) + (D² - Δ²)² - 4Δ²d² = 0,
    whose two roots are x = D/2 ∓ (|Δ|/2)·sqrt(1 + 4d²/(D² - Δ²)).  The root on the
    hyperbola branch of the measured sign (not the squaring's spurious one) satisfies
    D² - Δ² - 2Dx = 2Δ·r1, i.e. sign(D/2 - x) = sign(Δ), which selects

        x = D/2 - (Δ/2)·sqrt(1 + 4d²/(D² - Δ²)),

    unique because Δ(x) is strictly decreasing along the track.

    Parameters
    ----------
    delta_m : array_like of float
        Measured range difference r2 - r1 = c·t_{2,1} [m], any shape.
    geom : CellGeometry
        The cell geometry (d and the baseline D [m]).

    Returns
    -------
    x_m : numpy.ndarray of float
        Position on the track [m], the shape of ``delta_m``.  Where |Δ| >= D there is no
        solution (Δ(x) only tends to ±D as x → ∓∞); there ``x_m`` is ∓inf (the hyperbola's
        limit), to be clipped to the cell segment by :func:`clip_to_segment`.
    no_solution : numpy.ndarray of bool
        Boolean mask of |Δ| >= D, the shape of ``delta_m``.
    """
    delta = np.asarray(delta_m, dtype=float)
    big_d = geom.baseline_m
    no_solution = np.abs(delta) >= big_d
    with np.errstate(divide="ignore", invalid="ignore"):
        root = np.sqrt(1.0 + 4.0 * geom.d_m**2 / (big_d**2 - delta**2))
        x = 0.5 * big_d - 0.5 * delta * root
    x = np.where(no_solution, np.where(delta > 0, -np.inf, np.inf), x)
    return x, no_solution


def tdoa_on_track_rootfind(delta_m: float, geom: CellGeometry, span_m: float = 1e7) -> float:
    """Reference: the TDOA position by bracketing root finding (Brent) on r2 - r1 = Δ.

    A brute-force check of :func:`tdoa_on_track`, and the per-trial baseline of the
    benchmark.  Returns ±inf where |Δ| >= D, like the closed form.

    Parameters
    ----------
    delta_m : float
        Measured range difference r2 - r1 = c·t_{2,1} [m], a scalar.
    geom : CellGeometry
        The cell geometry.
    span_m : float, default 1e7
        Half width of the search bracket [-span_m, span_m] along the track [m].

    Returns
    -------
    float
        Position x on the track [m] (Brent, xtol 1e-9 m).  -sign(Δ)·inf where |Δ| >= D
        (no solution) or where the root lies beyond the bracket.
    """
    big_d = geom.baseline_m
    if abs(delta_m) >= big_d:
        return float(-np.sign(delta_m) * np.inf)

    def f(x: float) -> float:
        return float(geom.range_difference_m(x)) - delta_m

    lo, hi = -span_m, span_m
    if f(lo) < 0 or f(hi) > 0:  # root beyond the span: the solution is far off the cell
        return float(-np.sign(delta_m) * np.inf)
    return float(brentq(f, lo, hi, xtol=1e-9, rtol=1e-14, maxiter=500))


def aoa_on_track(theta_rad: ArrayLike, geom: CellGeometry) -> NDArray[np.float64]:
    """Intersection of the bearing line from BS1 with the track (source eq. 7, y = 0).

    y - d = tan(θ)·(x - 0) at y = 0 gives x = -d / tan θ [m].  θ = 0 or π (a bearing
    parallel to the track) gives ±inf, to be clipped by :func:`clip_to_segment`.

    Parameters
    ----------
    theta_rad : array_like of float
        Measured bearing θ of the train from BS1, counted from the +x direction of the track
        (as :meth:`CellGeometry.aoa_rad`) [rad], any shape.
    geom : CellGeometry
        The cell geometry (d [m]).

    Returns
    -------
    numpy.ndarray of float
        Position x = -d / tan θ on the track [m], the shape of ``theta_rad``; non-finite for
        a bearing parallel to the track.
    """
    theta = np.asarray(theta_rad, dtype=float)
    with np.errstate(divide="ignore"):
        return -geom.d_m / np.tan(theta)


def clip_to_segment(x_m: ArrayLike, geom: CellGeometry) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Clip positions to the serving cell's track segment; return them and the clip mask.

    The train is known to be in the serving cell, so an estimate outside its segment
    (or a TDOA without solution, ±inf) is projected onto the segment's nearer end.

    Parameters
    ----------
    x_m : array_like of float
        Position estimates on the track [m], any shape; ±inf allowed.
    geom : CellGeometry
        The cell geometry; its segment is [-sqrt(R² - d²), sqrt(R² - d²)] [m].

    Returns
    -------
    x_m : numpy.ndarray of float
        The positions clipped to the segment [m], the shape of ``x_m``.
    clipped : numpy.ndarray of bool
        Boolean mask of the positions that lay outside the segment, the shape of ``x_m``.
    """
    lo, hi = geom.segment_m
    x = np.asarray(x_m, dtype=float)
    clipped = (x < lo) | (x > hi)
    return np.clip(x, lo, hi), clipped


def tdoa_variance_propagated(x_m: ArrayLike, sigma_delta_m: float, geom: CellGeometry) -> NDArray[np.float64]:
    """First-order variance of the TDOA position at x [m²]: σ_Δ² / g(x)².

    Parameters
    ----------
    x_m : array_like of float
        Position(s) on the track at which the variance is evaluated (the true position, or
        the TDOA estimate when a receiver propagates it) [m], any shape.
    sigma_delta_m : float
        Standard deviation σ_Δ of the range-difference error, c·σ_TDOA [m].
    geom : CellGeometry
        The cell geometry.

    Returns
    -------
    numpy.ndarray of float
        Variance σ_Δ² / g(x)² of the TDOA position [m²], the shape of ``x_m``.
    """
    g = geom.range_difference_slope(x_m)
    return sigma_delta_m**2 / g**2


def aoa_variance_propagated(x_m: ArrayLike, sigma_theta_rad: float, geom: CellGeometry) -> NDArray[np.float64]:
    """First-order variance of the AOA position at x [m²]: σ_θ² · r1⁴ / d².

    Parameters
    ----------
    x_m : array_like of float
        Position(s) on the track at which the variance is evaluated (the true position, or
        the AOA estimate when a receiver propagates it) [m], any shape.
    sigma_theta_rad : float
        Standard deviation σ_θ of the AOA error at BS1 [rad].
    geom : CellGeometry
        The cell geometry.

    Returns
    -------
    numpy.ndarray of float
        Variance σ_θ² · r1⁴ / d² of the AOA position [m²], the shape of ``x_m``.
    """
    return sigma_theta_rad**2 / geom.aoa_slope(x_m) ** 2


def fuse(x_a: ArrayLike, var_a: ArrayLike, x_b: ArrayLike, var_b: ArrayLike) -> NDArray[np.float64]:
    """Inverse-variance weighted mean of two estimates (source eq. 9–10).

    x_F = (x_a/σ_a² + x_b/σ_b²) / (1/σ_a² + 1/σ_b²).  Variances must be > 0.

    Parameters
    ----------
    x_a : array_like of float
        First position estimate(s), e.g. the TDOA position [m].
    var_a : array_like of float
        Variance σ_a² of ``x_a`` [m²], > 0, broadcastable with ``x_a``.
    x_b : array_like of float
        Second position estimate(s), e.g. the AOA position [m].
    var_b : array_like of float
        Variance σ_b² of ``x_b`` [m²], > 0, broadcastable with ``x_b``.

    Returns
    -------
    numpy.ndarray of float
        The fused position x_F [m], the broadcast shape of the four inputs.

    Raises
    ------
    ValueError
        If a value of ``var_a`` or ``var_b`` is not > 0 (NaN included).
    """
    var_a = np.asarray(var_a, dtype=float)
    var_b = np.asarray(var_b, dtype=float)
    if np.any(~(var_a > 0)) or np.any(~(var_b > 0)):
        raise ValueError("var_a and var_b must be > 0 [m²]")
    w_a, w_b = 1.0 / var_a, 1.0 / var_b
    return (w_a * np.asarray(x_a) + w_b * np.asarray(x_b)) / (w_a + w_b)
