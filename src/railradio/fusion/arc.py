"""A curved track: the fusion study's cell layout on a circular arc (sensitivity, docs/model/fusion.md §5).

Source 002 uses the straight line y = 0 as the constraint.  Here the track is a
circular arc of radius R, tangent to y = 0 at the foot of the serving base station and
curving toward the base stations (the centre of curvature (0, R) lies on their side: the
BSs are *inside* the curve).  The cell layout is kept in along-track coordinates: the
unknown is the arc length s, the train is on s ∈ [0, L], L = sqrt(R_c² - d²) with
R_c = k·d the cell radius, the serving segment is s ∈ [-L, L], and BS k stands a distance d
from the track on the track's normal at s_k (s_1 = 0, s_2 = D = 2L).  With κ = 1/R:

    p(s)   = (sin κs / κ, (1 - cos κs) / κ)          track point
    t(s)   = (cos κs, sin κs)                         unit tangent
    n(s)   = (-sin κs, cos κs)                        unit normal toward the BSs
    b_k    = p(s_k) + d·n(s_k)                        BS k, on the circle of radius R - d

R = ∞ (κ = 0) is the source's straight track, exactly: p(s) = (s, 0), b_1 = (0, d),
b_2 = (D, d).  Inside the curve a bearing ray from BS1 leaves the circle exactly once, so
the AOA fix on the arc is unique; BSs outside the curve (a two-fold bearing ambiguity) are
not modelled.

Two estimators of s from a range difference Δ = r_2 - r_1 and a bearing θ at BS1:

* ``mismatch``: the source's estimator, which keeps the straight line y = 0 (the tangent at
  BS1's foot) as its constraint, with the true (surveyed) BS coordinates; its x on the line
  is its along-track coordinate.  Its error grows with the sagitta of the arc.
* ``arc``: the same estimators with the arc as the constraint — TDOA ∩ arc by a 1-D
  safeguarded Newton search on the monotone branch of Δ(s), AOA ∩ arc in closed form.

The Cramér–Rao bound on s (the along-track coordinate as the unknown) is

    J(s) = (dΔ/ds)² / σ_Δ² + (dθ/ds)² / σ_θ²,
    dΔ/ds = t·(p - b_2)/r_2 - t·(p - b_1)/r_1,  dθ/ds = ((p - b_1) × t) / r_1²,

the straight-track bound of :mod:`railradio.fusion.crlb` at κ = 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq

from railradio.fusion.estimators import aoa_on_track, tdoa_on_track
from railradio.fusion.geometry import CellGeometry


@dataclass(frozen=True)
class ArcGeometry:
    """The two-cell layout of :class:`CellGeometry` on a circular arc of radius ``radius_m``.

    Parameters
    ----------
    d_m : float
        Distance of both base stations from the track, along its normal [m], > 0.
    radius_m : float, default math.inf
        Radius of the track's circular arc [m]; ``math.inf`` is the straight track.  Must
        exceed ``d_m`` (the BSs lie inside the curve) and the baseline D must subtend less
        than π (R > D/π), so that the range difference decreases along [0, D].
    cell_radius_factor : float, default 2.0
        R_c / d (source: 2), > 1 [1].

    Raises
    ------
    ValueError
        If ``d_m`` or ``cell_radius_factor`` is out of range (as in :class:`CellGeometry`),
        ``radius_m`` is not > 0 (NaN included), or a finite ``radius_m`` is <= ``d_m`` or
        <= D/π.
    """

    d_m: float
    radius_m: float = math.inf
    cell_radius_factor: float = 2.0

    def __post_init__(self) -> None:
        cell = self.cell  # validates d_m and cell_radius_factor
        if not (self.radius_m > 0 and not math.isnan(self.radius_m)):
            raise ValueError(f"radius_m must be > 0 [m] or inf, got {self.radius_m!r}")
        if math.isfinite(self.radius_m):
            if self.radius_m <= self.d_m:
                raise ValueError(
                    f"radius_m must exceed d_m = {self.d_m} m (BSs inside the curve), got {self.radius_m!r}"
                )
            if cell.baseline_m / self.radius_m >= math.pi:
                raise ValueError(
                    f"radius_m must exceed D/pi = {cell.baseline_m / math.pi:.1f} m "
                    f"(the baseline D may subtend at most pi), got {self.radius_m!r}"
                )

    # --- layout -----------------------------------------------------------------------
    @cached_property
    def cell(self) -> CellGeometry:
        """The straight-track layout with the same d and cell radius."""
        return CellGeometry(self.d_m, self.cell_radius_factor)

    @property
    def curvature_per_m(self) -> float:
        """κ = 1/R [1/m] (0 for the straight track)."""
        return 0.0 if math.isinf(self.radius_m) else 1.0 / self.radius_m

    @property
    def is_straight(self) -> bool:
        return math.isinf(self.radius_m)

    @property
    def half_segment_m(self) -> float:
        """L = sqrt(R_c² - d²) [m], along the track."""
        return self.cell.half_segment_m

    @property
    def baseline_m(self) -> float:
        """Along-track distance D = 2L between the BSs' feet [m]."""
        return self.cell.baseline_m

    @property
    def segment_m(self) -> tuple[float, float]:
        """The serving cell's segment [-L, L] in arc length [m]."""
        return self.cell.segment_m

    @property
    def train_interval_m(self) -> tuple[float, float]:
        """Where the train is placed: s ∈ [0, L] [m]."""
        return self.cell.train_interval_m

    def sagitta_m(self, s_m: ArrayLike) -> NDArray[np.float64]:
        """Offset of the arc from its tangent line y = 0 at arc length s, (1 - cos κs)/κ [m].

        Parameters
        ----------
        s_m : array_like of float
            Arc length(s) s of the train along the track [m], any shape.

        Returns
        -------
        numpy.ndarray of float
            The sagitta (1 - cos κs)/κ [m], >= 0, the shape of ``s_m``; 0 on the straight
            track.
        """
        return self.track_xy_m(s_m)[1]

    def track_xy_m(self, s_m: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Track point p(s) = (sin κs/κ, (1 - cos κs)/κ) [m], written with sinc so that
        κ = 0 is the straight track exactly.

        Parameters
        ----------
        s_m : array_like of float
            Arc length(s) s of the train along the track [m], any shape.

        Returns
        -------
        x : numpy.ndarray of float
            x coordinate sin κs / κ of the track point [m], the shape of ``s_m``.
        y : numpy.ndarray of float
            y coordinate (1 - cos κs) / κ of the track point [m], the shape of ``s_m``.
        """
        s = np.asarray(s_m, dtype=float)
        k = self.curvature_per_m
        x = s * np.sinc(k * s / np.pi)
        y = s * np.sin(0.5 * k * s) * np.sinc(k * s / (2.0 * np.pi))
        return x, y

    def tangent(self, s_m: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Unit tangent t(s) = (cos κs, sin κs).

        Parameters
        ----------
        s_m : array_like of float
            Arc length(s) s of the train along the track [m], any shape.

        Returns
        -------
        tx : numpy.ndarray of float
            x component cos κs of the unit tangent in the direction of increasing s [1], the
            shape of ``s_m``.
        ty : numpy.ndarray of float
            y component sin κs of the unit tangent [1], the shape of ``s_m``.
        """
        a = self.curvature_per_m * np.asarray(s_m, dtype=float)
        return np.cos(a), np.sin(a)

    @cached_property
    def bs_xy_m(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """(BS1, BS2) coordinates [m]: b_k = p(s_k) + d·n(s_k), s_1 = 0, s_2 = D."""
        out = []
        for s_k in (0.0, self.baseline_m):
            px, py = self.track_xy_m(s_k)
            tx, ty = self.tangent(s_k)
            out.append((float(px - self.d_m * ty), float(py + self.d_m * tx)))
        return out[0], out[1]

    # --- measurement model ------------------------------------------------------------
    def ranges_m(self, s_m: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Distances r1, r2 [m] from the train at arc length s to BS1 and BS2.

        Parameters
        ----------
        s_m : array_like of float
            Arc length(s) s of the train along the track [m], any shape.

        Returns
        -------
        r1 : numpy.ndarray of float
            Distance from the track point p(s) to BS1 [m], the shape of ``s_m``.
        r2 : numpy.ndarray of float
            Distance from the track point p(s) to BS2 [m], the shape of ``s_m``.
        """
        px, py = self.track_xy_m(s_m)
        (x1, y1), (x2, y2) = self.bs_xy_m
        return np.hypot(px - x1, py - y1), np.hypot(px - x2, py - y2)

    def range_difference_m(self, s_m: ArrayLike) -> NDArray[np.float64]:
        """Δ(s) = r2 - r1 [m].

        Parameters
        ----------
        s_m : array_like of float
            Arc length(s) s of the train along the track [m], any shape.

        Returns
        -------
        numpy.ndarray of float
            The range difference r2 - r1 [m], the shape of ``s_m``.
        """
        r1, r2 = self.ranges_m(s_m)
        return r2 - r1

    def range_difference_slope(self, s_m: ArrayLike) -> NDArray[np.float64]:
        """dΔ/ds = t·(p - b2)/r2 - t·(p - b1)/r1 [m/m].

        Parameters
        ----------
        s_m : array_like of float
            Arc length(s) s of the train along the track [m], any shape.

        Returns
        -------
        numpy.ndarray of float
            Derivative of the range difference r2 - r1 with respect to the arc length [m/m],
            the shape of ``s_m``.
        """
        px, py = self.track_xy_m(s_m)
        tx, ty = self.tangent(s_m)
        (x1, y1), (x2, y2) = self.bs_xy_m
        r1, r2 = np.hypot(px - x1, py - y1), np.hypot(px - x2, py - y2)
        return (tx * (px - x2) + ty * (py - y2)) / r2 - (tx * (px - x1) + ty * (py - y1)) / r1

    def aoa_rad(self, s_m: ArrayLike) -> NDArray[np.float64]:
        """Bearing of the train from BS1, atan2(p_y - b1_y, p_x - b1_x) [rad].

        Parameters
        ----------
        s_m : array_like of float
            Arc length(s) s of the train along the track [m], any shape.

        Returns
        -------
        numpy.ndarray of float
            Bearing θ of the track point p(s) seen from BS1, counted from the +x direction
            [rad], in (-π, π], the shape of ``s_m``.
        """
        px, py = self.track_xy_m(s_m)
        (x1, y1), _ = self.bs_xy_m
        return np.arctan2(py - y1, px - x1)

    def aoa_slope(self, s_m: ArrayLike) -> NDArray[np.float64]:
        """dθ/ds = ((p - b1) × t) / r1² [rad/m] (d/r1² on the straight track).

        Parameters
        ----------
        s_m : array_like of float
            Arc length(s) s of the train along the track [m], any shape.

        Returns
        -------
        numpy.ndarray of float
            Derivative of the bearing at BS1 with respect to the arc length [rad/m], the shape
            of ``s_m``.
        """
        px, py = self.track_xy_m(s_m)
        tx, ty = self.tangent(s_m)
        (x1, y1), _ = self.bs_xy_m
        dx, dy = px - x1, py - y1
        return (dx * ty - dy * tx) / (dx * dx + dy * dy)

    @cached_property
    def tdoa_branch_m(self) -> tuple[float, float]:
        """(s_a, s_b): the branch of arc length around [0, D] on which Δ(s) decreases
        strictly; Δ(s_a) is the largest and Δ(s_b) the smallest range difference on the
        arc.  (-inf, inf) on the straight track.

        Δ is odd about the midpoint D/2 (Δ(D - s) = -Δ(s)), zero at the antipode of the
        midpoint, D/2 - πR, and increases from there to its maximum s_a < 0.
        """
        if self.is_straight:
            return (-math.inf, math.inf)
        half = 0.5 * self.baseline_m
        lo = half - math.pi * self.radius_m + 1e-9 * self.radius_m
        s_a = brentq(lambda s: float(self.range_difference_slope(s)), lo, 0.0, xtol=1e-9, rtol=1e-14, maxiter=500)
        return (s_a, self.baseline_m - s_a)


def fisher_information_arc(
    s_m: ArrayLike, sigma_delta_m: float, sigma_theta_rad: float, geom: ArcGeometry
) -> NDArray[np.float64]:
    """Fisher information J(s) about the along-track coordinate s [1/m²] (module docstring).

    Parameters
    ----------
    s_m : array_like of float
        Arc length(s) s of the train along the track [m], any shape.
    sigma_delta_m : float
        Standard deviation σ_Δ of the range-difference error, c·σ_TDOA [m], finite, > 0.
    sigma_theta_rad : float
        Standard deviation σ_θ of the AOA error at BS1 [rad], finite, > 0.
    geom : ArcGeometry
        The layout on the arc.

    Returns
    -------
    numpy.ndarray of float
        J(s) = (dΔ/ds)² / σ_Δ² + (dθ/ds)² / σ_θ² [1/m²], the shape of ``s_m``.

    Raises
    ------
    ValueError
        If ``sigma_delta_m`` or ``sigma_theta_rad`` is not a finite number > 0.
    """
    if not (sigma_delta_m > 0 and math.isfinite(sigma_delta_m)):
        raise ValueError(f"sigma_delta_m must be a finite number > 0, got {sigma_delta_m!r}")
    if not (sigma_theta_rad > 0 and math.isfinite(sigma_theta_rad)):
        raise ValueError(f"sigma_theta_rad must be a finite number > 0, got {sigma_theta_rad!r}")
    return geom.range_difference_slope(s_m) ** 2 / sigma_delta_m**2 + geom.aoa_slope(s_m) ** 2 / sigma_theta_rad**2


# --- estimators with the arc as the constraint ---------------------------------------
def tdoa_on_arc(
    delta_m: ArrayLike, geom: ArcGeometry, tol_m: float = 1e-9, max_iter: int = 200
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Arc length s with Δ(s) = Δ̂ on the branch (s_a, s_b) where Δ decreases strictly.

    A vectorized safeguarded Newton iteration: the bracket [lo, hi] around the root shrinks
    every step, a Newton step leaving it is replaced by bisection, so it converges for
    every Δ̂ in (Δ(s_b), Δ(s_a)).  Started by inverse linear interpolation of Δ tabulated
    on the branch (a few Newton steps then reach ``tol_m``).

    Parameters
    ----------
    delta_m : array_like of float
        Measured range difference Δ̂ = r2 - r1 [m], any shape.
    geom : ArcGeometry
        The layout on the arc.
    tol_m : float, default 1e-9
        Convergence tolerance on the step of the iteration [m], > 0 (a trial also stops when
        Δ(s) equals Δ̂ to rounding).  Unused on the straight track.
    max_iter : int, default 200
        Largest number of safeguarded Newton iterations.  Unused on the straight track.

    Returns
    -------
    s_m : numpy.ndarray of float
        The solution [m], the shape of ``delta_m``.  Where Δ̂ is outside the branch's range
        there is no solution; there s_m is the nearer end of the branch (the point of the
        arc whose range difference is nearest Δ̂) — ∓inf on the straight track, where this is
        exactly :func:`railradio.fusion.tdoa_on_track`.
    no_solution : numpy.ndarray of bool
        Boolean mask of the trials without solution, the shape of ``delta_m``.

    Raises
    ------
    ValueError
        If ``tol_m`` is not > 0.
    """
    if not tol_m > 0:
        raise ValueError(f"tol_m must be > 0, got {tol_m!r}")
    delta = np.asarray(delta_m, dtype=float)
    if geom.is_straight:
        return tdoa_on_track(delta, geom.cell)
    s_a, s_b = geom.tdoa_branch_m
    d_max = float(geom.range_difference_m(s_a))
    d_min = float(geom.range_difference_m(s_b))
    too_big, too_small = delta >= d_max, delta <= d_min
    no_solution = too_big | too_small
    target = np.where(no_solution, 0.0, delta)  # overwritten below; Δ(D/2) = 0 converges fast
    lo = np.full(delta.shape, s_a)
    hi = np.full(delta.shape, s_b)
    # start: inverse interpolation of Δ tabulated on the branch (Δ decreasing, so reversed)
    grid = np.linspace(s_a, s_b, 4097)
    s = np.interp(target, geom.range_difference_m(grid)[::-1], grid[::-1])
    f_tol = 8.0 * np.finfo(float).eps * (abs(d_max) + geom.baseline_m)
    for _ in range(max_iter):
        f = geom.range_difference_m(s) - target
        lo = np.where(f > 0, s, lo)  # Δ decreasing: Δ(s) above the target -> root to the right
        hi = np.where(f <= 0, s, hi)
        with np.errstate(divide="ignore", invalid="ignore"):
            s_new = s - f / geom.range_difference_slope(s)
        outside = ~((s_new >= lo) & (s_new <= hi))  # inclusive: a converged step is 0
        s_new = np.where(outside, 0.5 * (lo + hi), s_new)
        # converged: the step is below tol_m, or Δ(s) equals the target to rounding
        # (near the branch ends Δ' -> 0 and the step is rounding noise / Δ')
        done = (np.abs(s_new - s) <= tol_m) | (np.abs(f) <= f_tol)
        s = s_new
        if bool(np.all(done)):
            break
    s = np.where(too_big, s_a, np.where(too_small, s_b, s))
    return s, no_solution


def aoa_on_arc(theta_rad: ArrayLike, geom: ArcGeometry) -> NDArray[np.float64]:
    """Arc length where the bearing ray from BS1 = (0, d) meets the arc [m].

    The ray q = b1 + t·(cos θ, sin θ), t > 0, meets the circle |q - (0, R)| = R where
    t² + 2bt + c = 0, b = (d - R) sin θ, c = d² - 2dR < 0 (BS1 inside): the one positive
    root t = -c / (b + sqrt(b² - c)), written in κ so that it stays exact for large R;
    then s = atan2(κ q_x, 1 - κ q_y) / κ.  On the straight track this is
    :func:`railradio.fusion.aoa_on_track` (the source's eq. 7).

    Parameters
    ----------
    theta_rad : array_like of float
        Measured bearing θ of the train from BS1, counted from the +x direction (as
        :meth:`ArcGeometry.aoa_rad`) [rad], any shape.
    geom : ArcGeometry
        The layout on the arc.

    Returns
    -------
    numpy.ndarray of float
        Arc length s of the intersection [m], the shape of ``theta_rad``; in (-πR, πR] on a
        curved track.  On the straight track -d / tan θ, non-finite for a bearing parallel
        to the track.
    """
    theta = np.asarray(theta_rad, dtype=float)
    if geom.is_straight:
        return aoa_on_track(theta, geom.cell)
    k, d = geom.curvature_per_m, geom.d_m
    sin_t, cos_t = np.sin(theta), np.cos(theta)
    b = (1.0 - d * k) * sin_t  # b/R
    minus_c = 2.0 * d - d * d * k  # -c/R
    t = minus_c / (-b + np.sqrt(b * b + k * minus_c))
    qx, qy = t * cos_t, d + t * sin_t
    return np.arctan2(k * qx, 1.0 - k * qy) / k


def tdoa_variance_arc(s_m: ArrayLike, sigma_delta_m: float, geom: ArcGeometry) -> NDArray[np.float64]:
    """First-order variance of the TDOA arc position at s [m²]: σ_Δ² / (dΔ/ds)².

    Parameters
    ----------
    s_m : array_like of float
        Arc length(s) at which the variance is evaluated (the TDOA estimate when a receiver
        propagates it) [m], any shape.
    sigma_delta_m : float
        Standard deviation σ_Δ of the range-difference error, c·σ_TDOA [m].
    geom : ArcGeometry
        The layout on the arc.

    Returns
    -------
    numpy.ndarray of float
        Variance σ_Δ² / (dΔ/ds)² of the TDOA arc position [m²], the shape of ``s_m``.
    """
    return sigma_delta_m**2 / geom.range_difference_slope(s_m) ** 2


def aoa_variance_arc(s_m: ArrayLike, sigma_theta_rad: float, geom: ArcGeometry) -> NDArray[np.float64]:
    """First-order variance of the AOA arc position at s [m²]: σ_θ² / (dθ/ds)².

    Parameters
    ----------
    s_m : array_like of float
        Arc length(s) at which the variance is evaluated (the AOA estimate when a receiver
        propagates it) [m], any shape.
    sigma_theta_rad : float
        Standard deviation σ_θ of the AOA error at BS1 [rad].
    geom : ArcGeometry
        The layout on the arc.

    Returns
    -------
    numpy.ndarray of float
        Variance σ_θ² / (dθ/ds)² of the AOA arc position [m²], the shape of ``s_m``.
    """
    return sigma_theta_rad**2 / geom.aoa_slope(s_m) ** 2


# --- the source's straight-line estimator with general BS coordinates (mismatch) -----
def tdoa_on_line(
    delta_m: ArrayLike, d_m: float, bs2_xy_m: tuple[float, float]
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """TDOA ∩ the line y = 0 with BS1 at (0, d) and BS2 at (x2, y2), x2 > 0, in closed form.

    r2 = Δ + r1 squared gives A - 2x·x2 = 2Δ·r1 with A = x2² + y2² - d² - Δ²; squared again,
    4(x2² - Δ²)x² - 4A·x2·x + A² - 4Δ²d² = 0, with roots

        x± = (A·x2 ± Δ·S) / (2(x2² - Δ²)),   S = sqrt(A² + 4d²(x2² - Δ²)).

    A root is on the hyperbola branch of the measured sign when sign(A - 2x·x2) = sign Δ.
    For |Δ| < x2 exactly one is, x-, and Δ → ∓x2 as x → ±∞; with y2 = d, x2 = D this is the
    source's closed form (:func:`railradio.fusion.tdoa_on_track`).  With y2 ≠ d the range
    difference on the line is not monotone: for y2 > d it exceeds x2 behind BS1 (a maximum
    at some x_m < 0), so Δ slightly above x2 has two roots; the one on the branch through
    the cell (x > x_m, the larger root) is taken — the smaller for y2 < d, mirrored.  No
    valid root (Δ beyond the extremum) is a trial without solution: ∓inf, to be clipped to
    the segment as in the source.

    Parameters
    ----------
    delta_m : array_like of float
        Measured range difference Δ = r2 - r1 [m], any shape.
    d_m : float
        Distance of BS1 from the line: BS1 stands at (0, d) [m], finite, > 0.
    bs2_xy_m : tuple of float
        Coordinates (x2, y2) of BS2 [m], finite, x2 > 0 (e.g. :attr:`ArcGeometry.bs_xy_m`).

    Returns
    -------
    x_m : numpy.ndarray of float
        Position x on the line y = 0 [m], the shape of ``delta_m``; where there is no valid
        root, -inf for Δ > 0 and +inf otherwise.
    no_solution : numpy.ndarray of bool
        Boolean mask of the trials without a valid root (only possible for |Δ| >= x2), the
        shape of ``delta_m``.

    Raises
    ------
    ValueError
        If ``d_m`` is not a finite number > 0, or ``bs2_xy_m`` is not finite with x2 > 0.
    """
    x2, y2 = (float(v) for v in bs2_xy_m)
    if not (d_m > 0 and math.isfinite(d_m)):
        raise ValueError(f"d_m must be a finite number > 0, got {d_m!r}")
    if not (x2 > 0 and math.isfinite(x2) and math.isfinite(y2)):
        raise ValueError(f"bs2_xy_m must be finite with x2 > 0, got {bs2_xy_m!r}")
    delta = np.asarray(delta_m, dtype=float)
    den = x2 * x2 - delta * delta
    a = x2 * x2 + y2 * y2 - d_m * d_m - delta * delta
    disc = a * a + 4.0 * d_m * d_m * den
    with np.errstate(divide="ignore", invalid="ignore"):
        root = np.sqrt(disc)
        roots = [(a * x2 - delta * root) / (2.0 * den), (a * x2 + delta * root) / (2.0 * den)]
        valid = [(disc >= 0) & np.isfinite(r) & (np.sign(a - 2.0 * r * x2) == np.sign(delta)) for r in roots]
    # unique (x-) when |Δ| < x2; otherwise the valid root nearer the cell's branch
    prefer_larger = y2 > d_m
    both = valid[0] & valid[1]
    pick = np.where(prefer_larger, np.maximum(roots[0], roots[1]), np.minimum(roots[0], roots[1]))
    x = np.where(den > 0, roots[0], np.where(both, pick, np.where(valid[0], roots[0], roots[1])))
    no_solution = (den <= 0) & ~(valid[0] | valid[1])
    x = np.where(no_solution, np.where(delta > 0, -np.inf, np.inf), x)
    return x, no_solution


def line_range_difference_slope(x_m: ArrayLike, d_m: float, bs2_xy_m: tuple[float, float]) -> NDArray[np.float64]:
    """d(r2 - r1)/dx on the line y = 0 with BS1 at (0, d), BS2 at (x2, y2) [m/m].

    Parameters
    ----------
    x_m : array_like of float
        Position(s) x on the line y = 0 [m], any shape.
    d_m : float
        Distance of BS1 from the line: BS1 stands at (0, d) [m].
    bs2_xy_m : tuple of float
        Coordinates (x2, y2) of BS2 [m].

    Returns
    -------
    numpy.ndarray of float
        (x - x2)/r2 - x/r1, the derivative of the range difference along the line [m/m],
        the shape of ``x_m``.
    """
    x = np.asarray(x_m, dtype=float)
    x2, y2 = bs2_xy_m
    return (x - x2) / np.hypot(x - x2, y2) - x / np.hypot(x, d_m)
