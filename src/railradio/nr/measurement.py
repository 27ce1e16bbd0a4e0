"""Measurement model of the train tracker (seed eq. 13–14).

Per measured RRH k, h_k(s) = [atan2(y - y_k, x - x_k), ‖p - p_k‖/c] (seed eq. 14) with the
3-D range (known height difference). The innovation is y - h(ŝ⁻) (the seed's eq. 13
misprints a plus); angle innovations are wrapped to (-π, π].
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.antenna import wrap_rad

VARIANTS = {"aod": (True, False), "toa": (False, True), "aod_toa": (True, True)}
"""Measurement variants: which of (AOD, TOA) each RRH contributes (seed §4)."""


def h_terms(dx: NDArray, dy: NDArray, dh_m: float, variant: str) -> NDArray[np.float64]:
    """h per RRH, [..., per] (AOD [rad] then TOA [s]), from the train-minus-RRH offsets
    dx, dy [...] [m] (seed eq. 14, 3-D range with the known height difference)."""
    use_aod, use_toa = VARIANTS[variant]
    out = np.empty(np.shape(dx) + (int(use_aod) + int(use_toa),))
    if use_aod:
        out[..., 0] = np.arctan2(dy, dx)
    if use_toa:
        out[..., -1] = np.sqrt(dx**2 + dy**2 + dh_m**2) / SPEED_OF_LIGHT_M_S
    return out


def jac_terms(dx: NDArray, dy: NDArray, dh_m: float, variant: str) -> NDArray[np.float64]:
    """∂h/∂(x, y) per RRH, [..., per, 2], from the offsets dx, dy [...] [m]."""
    use_aod, use_toa = VARIANTS[variant]
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


def hx(s: NDArray, rrh_xy: NDArray, dh_m: float, variant: str) -> NDArray[np.float64]:
    """Stacked measurement function (seed eq. 14) for RRHs at ``rrh_xy`` [n, 2]."""
    h = h_terms(s[0] - rrh_xy[:, 0], s[1] - rrh_xy[:, 1], dh_m, variant)
    return h.ravel()  # [aod_0, toa_0, aod_1, toa_1, ...]


def jacobian(s: NDArray, rrh_xy: NDArray, dh_m: float, variant: str) -> NDArray[np.float64]:
    """Analytic ∂h/∂s at s: [n·m, 6] (only x, y enter)."""
    jac = jac_terms(s[0] - rrh_xy[:, 0], s[1] - rrh_xy[:, 1], dh_m, variant)
    out = np.zeros(jac.shape[:2] + (6,))
    out[..., :2] = jac
    return out.reshape(-1, 6)


def residual_fn(variant: str):
    """y - h with angle components wrapped to (-π, π]."""
    use_aod, use_toa = VARIANTS[variant]
    per = int(use_aod) + int(use_toa)

    def residual(a: NDArray, b: NDArray) -> NDArray:
        d = np.asarray(a, float) - np.asarray(b, float)
        if use_aod:
            d[0::per] = wrap_rad(d[0::per])
        return d

    return residual


def distances_m(s: NDArray, rrh_xy: NDArray) -> NDArray[np.float64]:
    """2-D distances [m] from the position in state (or position) ``s`` to ``rrh_xy`` [n, 2]."""
    return np.hypot(s[0] - rrh_xy[:, 0], s[1] - rrh_xy[:, 1])
