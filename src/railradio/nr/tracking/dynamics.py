"""Motion model of the train tracker (source eq. 10–12).

State s = [x, y, v_x, v_y, a_x, a_y] (source eq. 10), constant-acceleration transition
(source eq. 11–12) with white-jerk process noise of intensity q [m² s⁻⁵] [ours].
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def transition(dt_s: float) -> NDArray[np.float64]:
    """Constant-acceleration F for s = [x, y, vx, vy, ax, ay].

    Parameters
    ----------
    dt_s : float
        Epoch interval T [s].

    Returns
    -------
    numpy.ndarray
        [6, 6] transition matrix F (source eq. 11–12): entries 1, T [s] and T²/2 [s²].
    """
    f1 = np.array([[1.0, dt_s, 0.5 * dt_s**2], [0.0, 1.0, dt_s], [0.0, 0.0, 1.0]])
    return _interleave(f1)


def process_noise(dt_s: float, q: float) -> NDArray[np.float64]:
    """White-jerk process noise: per axis q·[[T⁵/20, T⁴/8, T³/6], [T⁴/8, T³/3, T²/2], [T³/6, T²/2, T]].

    Parameters
    ----------
    dt_s : float
        Epoch interval T [s].
    q : float
        White-jerk intensity [m² s⁻⁵].

    Returns
    -------
    numpy.ndarray
        [6, 6] process noise covariance Q on [x, y, vx, vy, ax, ay]: position block [m²],
        speed [m²/s²], acceleration [m²/s⁴] (x and y uncorrelated).
    """
    t = dt_s
    q1 = q * np.array([[t**5 / 20, t**4 / 8, t**3 / 6], [t**4 / 8, t**3 / 3, t**2 / 2], [t**3 / 6, t**2 / 2, t]])
    return _interleave(q1)


def _interleave(m: NDArray) -> NDArray[np.float64]:
    """Per-axis 3×3 [pos, vel, acc] block -> 6×6 on [x, y, vx, vy, ax, ay]."""
    return np.kron(m, np.eye(2))
