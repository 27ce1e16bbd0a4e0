"""The AOD's error near endfire: a bias by departure angle (docs/model/nr.md §6).

The AOD of source eq. 7 is the η-weighted mean of the beam angles of the 3 strongest detected
SS blocks. Toward endfire the beam grid ends: the strongest blocks of a train beyond the last
beam all lie on the broadside side of it, and their mean is pulled toward broadside. The error
is therefore not one zero-mean spread: it has a bias toward broadside that grows as the
departure angle nears endfire. It is measured on the calibration run (as W is) per bin of
the angle from endfire ψ = min(|θ|, π − |θ|) of the
azimuth θ = atan2(y − y_k, x − x_k) ∈ (−π, 0) (endfire: θ = 0 ahead of the RRH, θ = −π
behind), as a magnitude toward broadside (θ = −π/2), with one σ about it [ours]. The tracker
predicts each AOD as h(ŝ) + b(ψ̂) t(θ̂), t the direction toward broadside, with ψ̂ and θ̂ at
its prediction (never the truth).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def endfire_angle(aod_rad: NDArray) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The angle from endfire ψ [rad] and the direction toward broadside t (±1) of azimuths
    θ ∈ (−π, 0] (module docstring).

    Parameters
    ----------
    aod_rad : numpy.ndarray
        Azimuths of departure θ [rad], the tracker's convention (atan2(y − y_k, x − x_k)).

    Returns
    -------
    tuple of numpy.ndarray
        ψ ∈ [0, π/2] [rad] and t: −1 for |θ| < π/2 (broadside lies at smaller θ), +1 otherwise.
    """
    a = np.abs(np.asarray(aod_rad, float))
    return np.minimum(a, np.pi - a), np.where(a < np.pi / 2, -1.0, 1.0)


def bin_index(psi_rad: NDArray, edges_rad: tuple[float, ...]) -> NDArray[np.int64]:
    """The bin of each angle from endfire (an angle on an edge belongs to the lower bin).

    Parameters
    ----------
    psi_rad : numpy.ndarray
        Angles from endfire [rad].
    edges_rad : tuple of float
        Increasing bin edges [rad].

    Returns
    -------
    numpy.ndarray of int64
        Bin indices, 0 … len(edges_rad).
    """
    return np.searchsorted(np.asarray(edges_rad, float), np.asarray(psi_rad, float))


WINDOW_SIGMAS = 5.0
"""Half-width of the window, in pooled σ, about a bin's bias in which its errors count (the
rest, another RRH's peak or a false alarm, do not move it)."""


def fit(
    e_aod_rad: NDArray, aod_true_rad: NDArray, edges_rad: tuple[float, ...], spread, min_per_bin: int = 50
) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The bias toward broadside per bin of the true angle from endfire and one spread about
    it (the calibration run's errors, whose truth is known).

    Outliers first: σ₀ = ``spread`` of all errors (the pooled inlier σ). A bin's bias is found
    from 0 by iterating the median of its errors turned toward broadside, e t, within
    ±:data:`WINDOW_SIGMAS` σ₀ of the current value (a bin full of outliers, as far RRHs near
    endfire give a short run, cannot pull it to them). A bin with fewer than ``min_per_bin``
    errors in its window keeps the bias 0. The spread is one σ, ``spread`` of all errors
    less their bin's bias, for every bin: the bias is the structured part of eq. 7's error,
    and a σ per bin estimated from the tens of errors a short run leaves near endfire
    misled the tracker (docs/model/nr.md §6).

    Parameters
    ----------
    e_aod_rad : numpy.ndarray
        [N] AOD errors θ̂ − θ [rad], wrapped.
    aod_true_rad : numpy.ndarray
        [N] their true azimuths θ [rad].
    edges_rad : tuple of float
        Increasing bin edges of the angle from endfire [rad], in (0, π/2).
    spread : callable
        ``spread(errors) -> σ`` [rad] (the calibration's inlier σ).
    min_per_bin : int
        Fewest errors in a bin's window for its own bias.

    Returns
    -------
    tuple of tuple of float
        Bias toward broadside [rad] and σ [rad] per bin, ``len(edges_rad) + 1`` each (the σ
        the same in every bin).

    Raises
    ------
    ValueError
        When the edges are not increasing inside (0, π/2) or the arrays differ in shape.
    """
    edges = np.asarray(edges_rad, float)
    if edges.size == 0 or np.any(np.diff(edges) <= 0) or edges[0] <= 0 or edges[-1] >= np.pi / 2:
        raise ValueError(f"edges_rad must increase inside (0, pi/2), got {edges_rad!r}")
    e = np.asarray(e_aod_rad, float)
    th = np.asarray(aod_true_rad, float)
    if e.shape != th.shape:
        raise ValueError(f"e_aod_rad and aod_true_rad must share a shape, got {e.shape} and {th.shape}")
    ok = np.isfinite(e) & np.isfinite(th)
    e, th = e[ok], th[ok]
    psi, t = endfire_angle(th)
    b = bin_index(psi, tuple(edges))
    half = WINDOW_SIGMAS * float(spread(e))
    bias = np.zeros(edges.size + 1)
    for i in range(edges.size + 1):
        et = e[b == i] * t[b == i]
        c = 0.0
        for _ in range(50):  # until the median stays put
            near = et[np.abs(et - c) <= half]
            if near.size < min_per_bin:
                c = 0.0
                break
            c_new = float(np.median(near))
            if c_new == c:
                break
            c = c_new
        bias[i] = c
    sigma = float(spread(e - bias[b] * t))
    return tuple(float(x) for x in bias), (sigma,) * (edges.size + 1)


def predicted_bias(aod_pred_rad: NDArray, edges_rad: tuple[float, ...], bias_rad: tuple[float, ...]) -> NDArray:
    """The AOD bias b(ψ̂) t(θ̂) [rad] at predicted azimuths θ̂ [rad] (added to h).

    Parameters
    ----------
    aod_pred_rad : numpy.ndarray
        Predicted azimuths θ̂ [rad].
    edges_rad, bias_rad : tuple of float
        The model's bin edges and bias toward broadside per bin [rad] (:func:`fit`).

    Returns
    -------
    numpy.ndarray
        The bias of each prediction [rad], the shape of ``aod_pred_rad``.
    """
    psi, t = endfire_angle(aod_pred_rad)
    return np.asarray(bias_rad, float)[bin_index(psi, edges_rad)] * t
