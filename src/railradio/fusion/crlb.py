"""Cramér–Rao bound for the position on the track from one TDOA and one AOA.

With Δ̂ = Δ(x) + n_Δ, n_Δ ~ N(0, σ_Δ²) and θ̂ = θ(x) + n_θ, n_θ ~ N(0, σ_θ²)
independent, the Fisher information about the scalar track position x is

    J(x) = g(x)² / σ_Δ² + (dθ/dx)² / σ_θ²,   g = d(r2 - r1)/dx,  dθ/dx = d / r1²,

and any unbiased estimator has var(x̂) >= 1/J(x).  Over positions the study aggregates
the bound like the RMSE: sqrt(mean_x 1/J(x)).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from railradio.fusion.geometry import CellGeometry


def fisher_information(
    x_m: ArrayLike, sigma_delta_m: float, sigma_theta_rad: float, geom: CellGeometry
) -> NDArray[np.float64]:
    """Fisher information J(x) about the track position [1/m²].

    Parameters
    ----------
    x_m : array_like of float
        Train position(s) x on the track [m], any shape.
    sigma_delta_m : float
        Standard deviation σ_Δ of the range-difference error, c·σ_TDOA [m], > 0.
    sigma_theta_rad : float
        Standard deviation σ_θ of the AOA error at BS1 [rad], > 0.
    geom : CellGeometry
        The cell geometry (d and the baseline D [m]).

    Returns
    -------
    numpy.ndarray of float
        J(x) = g(x)² / σ_Δ² + (d / r1²)² / σ_θ² [1/m²], the shape of ``x_m``; 1/J(x) is the
        Cramér–Rao bound on the variance of an unbiased position estimate [m²].

    Raises
    ------
    ValueError
        If ``sigma_delta_m`` or ``sigma_theta_rad`` is not > 0.
    """
    if not sigma_delta_m > 0 or not sigma_theta_rad > 0:
        raise ValueError("sigma_delta_m and sigma_theta_rad must be > 0")
    g = geom.range_difference_slope(x_m)
    return g**2 / sigma_delta_m**2 + geom.aoa_slope(x_m) ** 2 / sigma_theta_rad**2


def crlb_rmse_m(x_m: ArrayLike, sigma_delta_m: float, sigma_theta_rad: float, geom: CellGeometry) -> float:
    """The bound aggregated over positions, sqrt(mean 1/J(x)) [m].

    Parameters
    ----------
    x_m : array_like of float
        Train positions x on the track over which the bound is aggregated [m], any shape.
    sigma_delta_m : float
        Standard deviation σ_Δ of the range-difference error, c·σ_TDOA [m], > 0.
    sigma_theta_rad : float
        Standard deviation σ_θ of the AOA error at BS1 [rad], > 0.
    geom : CellGeometry
        The cell geometry.

    Returns
    -------
    float
        The square root of the mean over ``x_m`` of 1/J(x) [m], aggregated like the RMSE.

    Raises
    ------
    ValueError
        If ``sigma_delta_m`` or ``sigma_theta_rad`` is not > 0.
    """
    return float(np.sqrt(np.mean(1.0 / fisher_information(x_m, sigma_delta_m, sigma_theta_rad, geom))))
