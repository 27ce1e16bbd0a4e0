"""Railway cell geometry of the fusion study (source 002, Fig. 2).

The track is the line y = 0.  The serving base station BS1 stands at (0, d) and the
neighbour BS2 at (D, d), both a distance d from the track on the same side.  The cell
radius is R = k·d (the source: k = 2), so the serving cell covers the track segment
|x| <= sqrt(R² - d²) and adjacent cells meet at half the baseline: D = 2·sqrt(R² - d²)
(= 2√3·d for k = 2).  The train is placed on [0, sqrt(R² - d²)] (source §3.1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray


@dataclass(frozen=True)
class CellGeometry:
    """Two base stations beside a straight track.

    Parameters
    ----------
    d_m : float
        Perpendicular distance of both base stations from the track [m], > 0.
    cell_radius_factor : float, default 2.0
        R / d, the cell radius in units of d (source: 2), > 1 [1].

    Raises
    ------
    ValueError
        If ``d_m`` is not a finite number > 0, or ``cell_radius_factor`` not a finite number > 1.
    """

    d_m: float
    cell_radius_factor: float = 2.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.d_m) and self.d_m > 0):
            raise ValueError(f"d_m must be a finite number > 0 [m], got {self.d_m!r}")
        if not (math.isfinite(self.cell_radius_factor) and self.cell_radius_factor > 1):
            raise ValueError(f"cell_radius_factor must be a finite number > 1, got {self.cell_radius_factor!r}")

    @property
    def cell_radius_m(self) -> float:
        """Cell radius R [m]."""
        return self.cell_radius_factor * self.d_m

    @property
    def half_segment_m(self) -> float:
        """Half length of the serving cell's track segment, sqrt(R² - d²) [m]."""
        return self.d_m * math.sqrt(self.cell_radius_factor**2 - 1.0)

    @property
    def baseline_m(self) -> float:
        """Distance D between BS1 and BS2 along the track [m]."""
        return 2.0 * self.half_segment_m

    @property
    def segment_m(self) -> tuple[float, float]:
        """The serving cell's track segment [x_lo, x_hi] [m]."""
        return (-self.half_segment_m, self.half_segment_m)

    @property
    def train_interval_m(self) -> tuple[float, float]:
        """Where the source places the train: [0, sqrt(R² - d²)] [m]."""
        return (0.0, self.half_segment_m)

    def ranges_m(self, x_m: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Distances r1, r2 [m] from a train at (x, 0) to BS1 and BS2 (source eq. 3).

        Parameters
        ----------
        x_m : array_like of float
            Train position(s) (x, 0) along the track [m], any shape.

        Returns
        -------
        r1 : numpy.ndarray of float
            Distance from the train to BS1 at (0, d) [m], the shape of ``x_m``.
        r2 : numpy.ndarray of float
            Distance from the train to BS2 at (D, d) [m], the shape of ``x_m``.
        """
        x = np.asarray(x_m, dtype=float)
        return np.hypot(x, self.d_m), np.hypot(self.baseline_m - x, self.d_m)

    def range_difference_m(self, x_m: ArrayLike) -> NDArray[np.float64]:
        """Range difference r2 - r1 [m] (source eq. 4), c times the TDOA t_{2,1}.

        Parameters
        ----------
        x_m : array_like of float
            Train position(s) (x, 0) along the track [m], any shape.

        Returns
        -------
        numpy.ndarray of float
            r2 - r1 [m], the shape of ``x_m``; in (-D, D), strictly decreasing in x.
        """
        r1, r2 = self.ranges_m(x_m)
        return r2 - r1

    def range_difference_slope(self, x_m: ArrayLike) -> NDArray[np.float64]:
        """g(x) = d(r2 - r1)/dx [m/m], negative everywhere on the track.

        Parameters
        ----------
        x_m : array_like of float
            Train position(s) (x, 0) along the track [m], any shape.

        Returns
        -------
        numpy.ndarray of float
            The slope g(x) = -(D - x)/r2 - x/r1 of the range difference [m/m], the shape of
            ``x_m``.
        """
        x = np.asarray(x_m, dtype=float)
        r1, r2 = self.ranges_m(x)
        return -(self.baseline_m - x) / r2 - x / r1

    def aoa_rad(self, x_m: ArrayLike) -> NDArray[np.float64]:
        """Angle of arrival at BS1 of the train's signal, atan2(0 - d, x - 0) [rad].

        Parameters
        ----------
        x_m : array_like of float
            Train position(s) (x, 0) along the track [m], any shape.

        Returns
        -------
        numpy.ndarray of float
            Bearing θ of the train seen from BS1, counted from the +x direction of the track
            [rad], the shape of ``x_m``; in (-π, 0), since the track lies below BS1.
        """
        x = np.asarray(x_m, dtype=float)
        return np.arctan2(-self.d_m, x)

    def aoa_slope(self, x_m: ArrayLike) -> NDArray[np.float64]:
        """dθ/dx = d / r1² [rad/m].

        Parameters
        ----------
        x_m : array_like of float
            Train position(s) (x, 0) along the track [m], any shape.

        Returns
        -------
        numpy.ndarray of float
            Rate of change of the bearing at BS1 with the train position, d / r1² [rad/m],
            positive, the shape of ``x_m``.
        """
        r1, _ = self.ranges_m(x_m)
        return self.d_m / r1**2
