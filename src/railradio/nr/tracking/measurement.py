"""Measurement model of the train tracker (source eq. 13–14).

Per measured RRH k, h_k(s) = [atan2(y - y_k, x - x_k), ‖p - p_k‖/c] (source eq. 14) with the
3-D range (known height difference). The innovation is y - h(ŝ⁻) (the source's eq. 13
misprints a plus); angle innovations are wrapped to (-π, π].
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.channel.antenna import wrap_rad

MEASUREMENT_SETS = {"aod": (True, False), "toa": (False, True), "aod_toa": (True, True)}
"""Measurement sets: which of (AOD, TOA) each RRH contributes (source §4)."""


def h_terms(dx: NDArray, dy: NDArray, dh_m: float, measurements: str) -> NDArray[np.float64]:
    """h per RRH, [..., per] (AOD [rad] then TOA [s]), from the train-minus-RRH offsets
    dx, dy [...] [m] (source eq. 14, 3-D range with the known height difference).

    Parameters
    ----------
    dx, dy : numpy.ndarray
        Train-minus-RRH offsets along and across the track [m], same shape [...].
    dh_m : float
        Height difference between the RRHs and the train antenna [m].
    measurements : str
        Measurement set: ``aod``, ``toa`` or ``aod_toa`` (:data:`MEASUREMENT_SETS`).

    Returns
    -------
    numpy.ndarray
        [..., per] (per = 1 or 2 measurements per RRH): AOD atan2(dy, dx) [rad] then TOA
        (3-D distance over c) [s], as used by the measurement set.

    Raises
    ------
    KeyError
        When ``measurements`` is not a key of :data:`MEASUREMENT_SETS`.
    """
    use_aod, use_toa = MEASUREMENT_SETS[measurements]
    out = np.empty(np.shape(dx) + (int(use_aod) + int(use_toa),))
    if use_aod:
        out[..., 0] = np.arctan2(dy, dx)
    if use_toa:
        out[..., -1] = np.sqrt(dx**2 + dy**2 + dh_m**2) / SPEED_OF_LIGHT_M_S
    return out


def jac_terms(dx: NDArray, dy: NDArray, dh_m: float, measurements: str) -> NDArray[np.float64]:
    """∂h/∂(x, y) per RRH, [..., per, 2], from the offsets dx, dy [...] [m].

    Parameters
    ----------
    dx, dy : numpy.ndarray
        Train-minus-RRH offsets along and across the track [m], same shape [...].
    dh_m : float
        Height difference between the RRHs and the train antenna [m].
    measurements : str
        Measurement set: ``aod``, ``toa`` or ``aod_toa`` (:data:`MEASUREMENT_SETS`).

    Returns
    -------
    numpy.ndarray
        [..., per, 2] derivatives by the train's x and y: AOD row [rad/m], TOA row [s/m].

    Raises
    ------
    KeyError
        When ``measurements`` is not a key of :data:`MEASUREMENT_SETS`.
    """
    use_aod, use_toa = MEASUREMENT_SETS[measurements]
    out = np.empty(np.shape(dx) + (int(use_aod) + int(use_toa), 2))
    if use_aod:
        r2 = dx**2 + dy**2
        out[..., 0, 0] = -dy / r2
        out[..., 0, 1] = dx / r2
    if use_toa:
        r3 = np.sqrt(dx**2 + dy**2 + dh_m**2) * SPEED_OF_LIGHT_M_S
        out[..., -1, 0] = dx / r3
        out[..., -1, 1] = dy / r3
    return out


def hx(s: NDArray, rrh_xy: NDArray, dh_m: float, measurements: str) -> NDArray[np.float64]:
    """Stacked measurement function (source eq. 14) for RRHs at ``rrh_xy`` [n, 2].

    Parameters
    ----------
    s : numpy.ndarray
        State [6] (x, y [m] first; the rest is not used).
    rrh_xy : numpy.ndarray
        [n, 2] RRH positions (x, y) [m].
    dh_m : float
        Height difference between the RRHs and the train antenna [m].
    measurements : str
        Measurement set: ``aod``, ``toa`` or ``aod_toa`` (:data:`MEASUREMENT_SETS`).

    Returns
    -------
    numpy.ndarray
        [n·per] predicted measurements [aod_0, toa_0, aod_1, ...] (AOD [rad], TOA [s]).

    Raises
    ------
    KeyError
        When ``measurements`` is not a key of :data:`MEASUREMENT_SETS`.
    """
    h = h_terms(s[0] - rrh_xy[:, 0], s[1] - rrh_xy[:, 1], dh_m, measurements)
    return h.ravel()  # [aod_0, toa_0, aod_1, toa_1, ...]


def jacobian(s: NDArray, rrh_xy: NDArray, dh_m: float, measurements: str) -> NDArray[np.float64]:
    """Analytic ∂h/∂s at s: [n·m, 6] (only x, y enter).

    Parameters
    ----------
    s : numpy.ndarray
        State [6] (x, y [m] first).
    rrh_xy : numpy.ndarray
        [n, 2] RRH positions (x, y) [m].
    dh_m : float
        Height difference between the RRHs and the train antenna [m].
    measurements : str
        Measurement set: ``aod``, ``toa`` or ``aod_toa`` (:data:`MEASUREMENT_SETS`).

    Returns
    -------
    numpy.ndarray
        [n·per, 6] Jacobian, rows ordered as :func:`hx`: AOD rows [rad/m], TOA rows [s/m] in
        the x, y columns, zero in the speed and acceleration columns.

    Raises
    ------
    KeyError
        When ``measurements`` is not a key of :data:`MEASUREMENT_SETS`.
    """
    jac = jac_terms(s[0] - rrh_xy[:, 0], s[1] - rrh_xy[:, 1], dh_m, measurements)
    out = np.zeros(jac.shape[:2] + (6,))
    out[..., :2] = jac
    return out.reshape(-1, 6)


def residual_fn(measurements: str):
    """y - h with angle components wrapped to (-π, π].

    Parameters
    ----------
    measurements : str
        Measurement set: ``aod``, ``toa`` or ``aod_toa`` (:data:`MEASUREMENT_SETS`).

    Returns
    -------
    callable
        ``residual(a, b) -> a - b`` for stacked measurement vectors [n·per] (as :func:`hx`),
        with the AOD components [rad] wrapped; TOA components [s] unchanged.

    Raises
    ------
    KeyError
        When ``measurements`` is not a key of :data:`MEASUREMENT_SETS`.
    """
    use_aod, use_toa = MEASUREMENT_SETS[measurements]
    per = int(use_aod) + int(use_toa)

    def residual(a: NDArray, b: NDArray) -> NDArray:
        d = np.asarray(a, float) - np.asarray(b, float)
        if use_aod:
            d[0::per] = wrap_rad(d[0::per])
        return d

    return residual


def distances_m(s: NDArray, rrh_xy: NDArray) -> NDArray[np.float64]:
    """2-D distances [m] from the position in state (or position) ``s`` to ``rrh_xy`` [n, 2].

    Parameters
    ----------
    s : numpy.ndarray
        State [6] or position [2], x, y [m] first.
    rrh_xy : numpy.ndarray
        [n, 2] RRH positions (x, y) [m].

    Returns
    -------
    numpy.ndarray
        [n] horizontal distances [m].
    """
    return np.hypot(s[0] - rrh_xy[:, 0], s[1] - rrh_xy[:, 1])
