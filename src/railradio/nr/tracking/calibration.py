"""Calibration of the train tracker on a calibration run (never the evaluation run): the
measurement errors of the selected candidates, their robust spreads (W) and the white-jerk
intensity q whose position NEES is consistent [ours]."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2, median_abs_deviation

import railradio.nr.tracking.aod_model as aod_model
from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.channel.antenna import wrap_rad
from railradio.nr.tracking.ekf import TrackerConfig, nees_position
from railradio.nr.tracking.track import track


def selected(ds, strength: str = "peak", n_use: int = 3) -> tuple[NDArray, NDArray]:
    """The candidates a receiver measures per epoch: ``(order, ok)``, [epoch, n_use] column
    indices of the ``n_use`` strongest by ``strength`` among those with an AOD and a TOA,
    and whether each holds a measurement.

    Parameters
    ----------
    ds : xarray.Dataset
        One receiver's estimates (a :func:`railradio.nr.engine.epochs.simulate_epochs` dataset
        selected at one ``receiver``): ``aod_hat`` [rad], ``toa_hat`` [s], their truths
        ``aod_true``, ``toa_true``, and the strength variables, dims (``epoch``, ``cand``).
    strength : str
        Variable ranking the candidates (the receiver's selection): ``"peak"`` (combined
        correlation peak), ``"ss_rsrp"`` or ``"best_score"``.
    n_use : int
        Candidates measured per epoch.

    Returns
    -------
    order : numpy.ndarray of int
        [epoch, n_use] candidate (``cand``) indices, strongest first.
    ok : numpy.ndarray of bool
        [epoch, n_use] whether each holds an AOD and a TOA.
    """
    ok = np.isfinite(ds["aod_hat"].values) & np.isfinite(ds["toa_hat"].values)
    s = np.where(ok, np.nan_to_num(ds[strength].values, nan=-np.inf), -np.inf)
    order = np.argsort(-s, axis=1)[:, :n_use]
    return order, np.take_along_axis(ok, order, axis=1)


def measurement_errors(
    ds, strength: str = "peak", n_use: int = 3, flat: bool = True, with_distance: bool = False
) -> tuple[NDArray, ...]:
    """AOD [rad, wrapped] and TOA range [m] errors of the measurements the tracker would use
    (the ``n_use`` strongest detected candidates per epoch); ``flat=False`` returns
    [epoch, n_use] arrays with NaN where fewer were detected. ``with_distance`` also
    returns (flat only) the true 3-D distances [m] of those measurements.

    Parameters
    ----------
    ds : xarray.Dataset
        One receiver's estimates (a :func:`railradio.nr.engine.epochs.simulate_epochs` dataset
        selected at one ``receiver``): ``aod_hat`` [rad], ``toa_hat`` [s], their truths
        ``aod_true``, ``toa_true``, and the strength variables, dims (``epoch``, ``cand``).
        Also ``d3d`` [m] with ``with_distance``.
    strength : str
        Variable ranking the candidates (the receiver's selection): ``"peak"`` (combined
        correlation peak), ``"ss_rsrp"`` or ``"best_score"``.
    n_use : int
        Candidates measured per epoch.
    flat : bool
        Return the detected errors as 1-D arrays (True) or [epoch, n_use] arrays (False).
    with_distance : bool
        Also return the true 3-D distances, m (only with ``flat``).

    Returns
    -------
    tuple of numpy.ndarray
        ``(e_aod_rad, e_range_m)`` (AOD error [rad] wrapped to (-π, π], range error c·Δτ [m]),
        plus ``d3d_m`` [m] with ``with_distance``.
    """
    aod = ds["aod_hat"].values
    toa = ds["toa_hat"].values
    order, sel_ok = selected(ds, strength, n_use)
    e_aod = wrap_rad(np.take_along_axis(aod - ds["aod_true"].values, order, axis=1))
    e_rng = np.take_along_axis(toa - ds["toa_true"].values, order, axis=1) * SPEED_OF_LIGHT_M_S
    if not flat:
        return np.where(sel_ok, e_aod, np.nan), np.where(sel_ok, e_rng, np.nan)
    if with_distance:
        return e_aod[sel_ok], e_rng[sel_ok], np.take_along_axis(ds["d3d"].values, order, axis=1)[sel_ok]
    return e_aod[sel_ok], e_rng[sel_ok]


def inlier_sigma(e: NDArray, gate_prob: float = 0.99, n_iter: int = 50) -> tuple[float, float]:
    """Standard deviation of the inliers of errors ``e`` and their share: the errors a χ²₁
    gate at ``gate_prob`` keeps (|e − median| ≤ k σ, k = √χ²₁(gate_prob)), with σ the
    inliers' own spread corrected for the truncation at ±k (a normal truncated there has
    variance σ² [1 − 2kφ(k)/(2Φ(k) − 1)]); a fixed point started from 1.4826 · MAD. The
    outliers (another RRH's peak, a false detection) then do not set W [ours].

    Parameters
    ----------
    e : numpy.ndarray
        Errors, any shape and unit (e.g. AOD [rad] or range [m]); NaN entries are ignored.
    gate_prob : float
        χ²₁ gate probability [1], in (0, 1).
    n_iter : int
        Most fixed-point iterations.

    Returns
    -------
    tuple of float
        ``(sigma, share)``: the inliers' standard deviation, in the unit of ``e``, and the share
        of the finite errors that are inliers [1]; (NaN, 0) without finite errors.
    """
    from scipy.stats import norm

    e = np.asarray(e, float)
    e = e[np.isfinite(e)]
    if e.size == 0:
        return float("nan"), 0.0
    k = float(np.sqrt(chi2.ppf(gate_prob, 1)))
    shrink = 1.0 - 2 * k * norm.pdf(k) / (2 * norm.cdf(k) - 1)
    c = float(np.median(e))
    sig = 1.4826 * float(median_abs_deviation(e, axis=None))  # median |e - c|
    inl = np.ones(e.size, dtype=bool)
    for _ in range(n_iter):
        if not sig > 0:
            break
        inl = np.abs(e - c) <= k * sig
        new = float(np.std(e[inl]) / np.sqrt(shrink)) if inl.sum() > 1 else sig
        c = float(np.mean(e[inl]))
        if abs(new - sig) <= 1e-9 * sig:
            sig = new
            break
        sig = new
    return sig, float(inl.mean())


def robust_sigmas(
    e_aod_rad: NDArray,
    e_range_m: NDArray,
    dist_m: NDArray,
    distance_edges_m: tuple[float, ...] = (),
    min_per_bin: int = 50,
    fs_hz: float = 245.76e6,
    gate_prob: float = 0.99,
) -> tuple[float, float, dict]:
    """σ_AOD [rad] and σ_TOA [s] of the calibration errors' inliers (:func:`inlier_sigma`
    at ``gate_prob``), σ_TOA floored at the integer-sample quantization 1/(√12 F_s); with
    ``distance_edges_m`` also per bin of ``dist_m`` (a bin with fewer than ``min_per_bin``
    errors takes the overall values), returned as :class:`TrackerConfig` keyword arguments.

    Parameters
    ----------
    e_aod_rad : numpy.ndarray
        [N] AOD errors [rad] (wrapped).
    e_range_m : numpy.ndarray
        [N] TOA range errors c·Δτ [m].
    dist_m : numpy.ndarray
        [N] 2-D train–RRH distances of those measurements [m] (used only with bins).
    distance_edges_m : tuple of float
        Increasing distance bin edges [m]; empty: no bins.
    min_per_bin : int
        Fewest errors for a bin's own σ values.
    fs_hz : float
        Sample rate F_s [Hz] of the TOA quantization floor.
    gate_prob : float
        χ²₁ gate probability [1] of :func:`inlier_sigma`.

    Returns
    -------
    tuple of (float, float, dict)
        σ_AOD [rad] (at least 1e-4 rad), σ_TOA [s] (at least 1/(√12 F_s)); both NaN without
        errors; and, with bins,
        ``distance_edges_m`` [m], ``sigma_aod_bins_rad`` [rad], ``sigma_toa_bins_s`` [s] (one
        entry per bin, ``len(distance_edges_m) + 1``); an empty dict without bins.
    """

    def spread(e):
        return inlier_sigma(e, gate_prob)[0] if e.size else np.nan

    floor = 1.0 / (np.sqrt(12) * fs_hz)
    s_aod = max(spread(e_aod_rad), 1e-4)
    s_toa = max(spread(e_range_m) / SPEED_OF_LIGHT_M_S, floor)
    if not distance_edges_m:
        return s_aod, s_toa, {}
    b = np.searchsorted(np.asarray(distance_edges_m, float), dist_m)
    a_bins, t_bins = [], []
    for i in range(len(distance_edges_m) + 1):
        m = b == i
        if m.sum() < min_per_bin:
            a_bins.append(s_aod)
            t_bins.append(s_toa)
        else:
            a_bins.append(max(spread(e_aod_rad[m]), 1e-4))
            t_bins.append(max(spread(e_range_m[m]) / SPEED_OF_LIGHT_M_S, floor))
    return (
        s_aod,
        s_toa,
        dict(
            distance_edges_m=tuple(float(x) for x in distance_edges_m),
            sigma_aod_bins_rad=tuple(a_bins),
            sigma_toa_bins_s=tuple(t_bins),
        ),
    )


Q_SEARCH_LIMITS = (1e-6, 1e6)
"""The widest q [m² s⁻⁵] the calibration searches when its grid's edge wins [ours]."""


def _nees_cost(ds, out) -> float:
    """|log(median NEES / median χ²₂)| of the position over the calibration run's tracked
    epochs: 0 for a filter whose covariance matches its errors."""
    nees = nees_position(out["state"], out["cov"], ds["x_true"].values)
    nees = nees[np.isfinite(nees)]
    if nees.size < 10:
        return np.inf
    return abs(float(np.log(np.median(nees) / chi2.median(2))))


def calibrate(
    ds,
    measurements: str,
    rrh_x: NDArray,
    rrh_y: float,
    dh_m: float,
    dt_s: float,
    q_grid: NDArray,
    gate: bool,
    strength: str = "peak",
    fs_hz: float = 245.76e6,
    distance_edges_m: tuple[float, ...] = (),
    min_per_bin: int = 50,
    gate_prob: float = 0.99,
    search: dict | None = None,
    start_speed_sigma_m_s: float = 1.0,
    aod_angle_edges_rad: tuple[float, ...] = (),
) -> TrackerConfig:
    """Measurement and process noise from a calibration run (never the evaluation run).

    W: σ_AOD, σ_TOA of the inliers of the selected measurements' errors, those a χ² gate
    at ``gate_prob`` keeps (:func:`inlier_sigma`), the TOA one floored at the
    integer-sample quantization 1/(√12 F_s); with ``distance_edges_m``, also per bin of the
    true 2-D distance (a bin with fewer than ``min_per_bin`` measurements takes the overall
    values); with ``aod_angle_edges_rad``, the AOD's bias toward broadside and σ per bin of
    the true angle from endfire (:func:`railradio.nr.tracking.aod_model.fit`), with which the
    tracker predicts and weights each AOD. q: the value whose position NEES on the calibration run (whose truth is
    legitimately known) is consistent, |log(median NEES / median χ²₂)| smallest, over
    ``q_grid``; when an edge of the grid wins, the grid is extended by decades beyond it up
    to :data:`Q_SEARCH_LIMITS`. ``search`` (a dict) receives the q values tried, their
    costs, whether the winner sits on the searched range's edge and whether the cost is
    monotone toward it (the search reached the limit with the cost falling at every decade
    from the grid's edge on: no q is identified, the finding to report instead of a q).

    Parameters
    ----------
    ds : xarray.Dataset
        One receiver's estimates (a :func:`railradio.nr.engine.epochs.simulate_epochs` dataset
        selected at one ``receiver``): ``aod_hat`` [rad], ``toa_hat`` [s], their truths
        ``aod_true``, ``toa_true``, and the strength variables, dims (``epoch``, ``cand``).
    measurements : str
        Measurement set: ``aod``, ``toa`` or ``aod_toa``.
    rrh_x : numpy.ndarray
        Along-track positions of the RRHs, m (``Deployment.x_m``).
    rrh_y : float
        Lateral offset of the RRHs from the track, m (``Deployment.offset_m``).
    dh_m : float
        RRH height above the train antenna, m (``h_bs_m - h_ut_m``).
    dt_s : float
        Epoch interval, s.
    q_grid : numpy.ndarray
        Candidate white-jerk intensities q, m² s⁻⁵ (must not be empty).
    gate : bool
        Whether the tracker runs with the χ² innovation gate.
    strength : str
        Variable ranking the candidates (the receiver's selection): ``"peak"`` (combined
        correlation peak), ``"ss_rsrp"`` or ``"best_score"``.
    fs_hz : float
        Sample rate F_s, Hz, of the TOA quantization floor 1/(√12 F_s).
    distance_edges_m : tuple of float
        Increasing 2-D train–RRH distance bin edges, m (empty: one W for all distances).
    min_per_bin : int
        Fewest measurements for a bin's own σ values.
    gate_prob : float
        χ² gate probability (1), in (0, 1).
    search : dict or None
        Filled with the q search record (see above) when given.
    start_speed_sigma_m_s : float
        σ of the initial speed about 0, m/s (> 0).
    aod_angle_edges_rad : tuple of float
        Increasing angle-from-endfire bin edges inside (0, π/2), rad (empty: no AOD model).

    Returns
    -------
    TrackerConfig
        The calibrated tracker: ``q`` [m² s⁻⁵], ``sigma_aod_rad`` [rad], ``sigma_toa_s`` [s] and
        any per-bin values.

    Raises
    ------
    ValueError
        When ``q_grid`` is empty, or (from :class:`TrackerConfig`) a calibrated σ is not > 0.
    """
    e_aod, e_rng, d3 = measurement_errors(ds, strength, with_distance=True)
    dist = np.sqrt(np.maximum(d3**2 - dh_m**2, 0.0))  # 2-D, as the tracker predicts it
    s_aod, s_toa, bins = robust_sigmas(e_aod, e_rng, dist, distance_edges_m, min_per_bin, fs_hz, gate_prob)
    if aod_angle_edges_rad:
        order, ok = selected(ds, strength)
        aod_true = np.take_along_axis(ds["aod_true"].values, order, axis=1)[ok]  # as e_aod's
        bias, sig = aod_model.fit(
            e_aod, aod_true, tuple(aod_angle_edges_rad), lambda e: max(inlier_sigma(e, gate_prob)[0], 1e-4), min_per_bin
        )
        bins |= dict(
            aod_angle_edges_rad=tuple(float(x) for x in aod_angle_edges_rad),
            aod_bias_bins_rad=bias,
            sigma_aod_angle_bins_rad=sig,
        )
    qs = sorted(float(q) for q in q_grid)
    if not qs:
        raise ValueError("q_grid must not be empty")
    cost: dict[float, float] = {}

    def cfg_of(q):
        return TrackerConfig(
            measurements=measurements,
            q=q,
            sigma_aod_rad=s_aod,
            sigma_toa_s=s_toa,
            gate=gate,
            gate_prob=gate_prob,
            start_speed_sigma_m_s=start_speed_sigma_m_s,
            **bins,
        )

    def run(q):
        if q not in cost:
            cost[q] = _nees_cost(ds, track(ds, rrh_x, rrh_y, dh_m, dt_s, cfg_of(q), strength=strength, snapshot=False))
        return cost[q]

    best = _search_q(run, cost, qs)
    if search is not None:
        search.update(_search_record(cost, qs, best))
    return cfg_of(best)


def _search_q(run, cost: dict[float, float], qs: list[float]) -> float:
    """The q [m² s⁻⁵] of smallest cost: ``run(q)`` fills ``cost`` for every q of the sorted
    grid ``qs``, then for a decade beyond the grid's edge while the edge wins, up to
    :data:`Q_SEARCH_LIMITS` (ties: the smaller q)."""
    for q in qs:
        run(q)
    lo, hi = Q_SEARCH_LIMITS
    while True:
        tried = sorted(cost)
        best = min(tried, key=lambda q: (cost[q], q))
        if best == tried[0] and best / 10 >= lo and np.isfinite(cost[best]):
            run(best / 10)
        elif best == tried[-1] and best * 10 <= hi and np.isfinite(cost[best]):
            run(best * 10)
        else:
            break
    return best


def _search_record(cost: dict[float, float], qs: list[float], best: float) -> dict:
    """What :func:`calibrate` reports of its q search (its ``search`` dict): the q values
    tried, their costs (None where infinite), whether the winner ``best`` sits on the
    searched range's edge and whether the cost is monotone toward it."""
    lo, hi = Q_SEARCH_LIMITS
    tried = sorted(cost)
    c = np.array([cost[q] for q in tried])
    # monotone toward the edge: the search widened to the limit and the cost fell at
    # every decade from the grid's edge on (no minimum inside the limits)
    if best == tried[-1] and best * 10 > hi:
        toward = c[np.asarray(tried) >= qs[-1]]
    elif best == tried[0] and best / 10 < lo:
        toward = c[np.asarray(tried) <= qs[0]][::-1]
    else:
        toward = np.array([])
    return dict(
        q=tried,
        cost=[float(v) if np.isfinite(v) else None for v in c],
        at_edge=bool(best in (tried[0], tried[-1])),
        monotone=bool(toward.size > 1 and np.all(np.isfinite(toward)) and np.all(np.diff(toward) < 0)),
    )
