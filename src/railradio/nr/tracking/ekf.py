"""The extended Kalman filter of the train tracker (source eq. 10–14; docs/model/nr.md §6, EKF).

The motion model (:mod:`railradio.nr.tracking.dynamics`, source eq. 10–12) and the measurement model
(:mod:`railradio.nr.tracking.measurement`, source eq. 13–14) in an extended Kalman filter:
filterpy's ExtendedKalmanFilter does the algebra; a χ² gate per RRH is an option. Here are
the filter's settings (:class:`TrackerConfig`: measurement set, q, W, gate), its run over the epochs
(:func:`run_ekf`, measurements chosen by a caller-given ``select``, re-acquisition by a
caller-given ``reacquire``) and the position NEES that scores its consistency. Which
measurements it is given is :mod:`railradio.nr.tracking.candidates`; a whole track is
:mod:`railradio.nr.tracking.track`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter
from numpy.typing import NDArray
from scipy.stats import chi2

import railradio.nr.tracking.aod_model as aod_model
from railradio.nr.tracking.dynamics import process_noise, transition
from railradio.nr.tracking.measurement import MEASUREMENT_SETS, h_terms, jac_terms, residual_fn

Select = Callable[[int, NDArray], tuple[NDArray, NDArray, NDArray]]
"""``select(n, x_pred) -> (rrh_xy [m_n, 2], aod [m_n], toa [m_n])``: the measurements of
epoch n, chosen from the predicted state ``x_pred`` [6]."""
Reacquire = Callable[[int], tuple[NDArray, NDArray] | None]
"""``reacquire(n) -> (position [2], covariance [2, 2]) | None``: a position fix at epoch n."""
LATERAL = [1, 3, 5]
"""Indices of y, v_y and a_y in the state (x, y, v_x, v_y, a_x, a_y)."""
_DISTANCE_BINS = ("distance_edges_m", "sigma_aod_bins_rad", "sigma_toa_bins_s")
_ANGLE_BINS = ("aod_angle_edges_rad", "aod_bias_bins_rad", "sigma_aod_angle_bins_rad")


@dataclass(frozen=True)
class TrackerConfig:
    """Tracker settings [ours unless noted].

    measurements: the measurement set, ``aod``, ``toa`` or ``aod_toa`` [source]; q: white-jerk intensity [m² s⁻⁵];
    sigma_aod_rad, sigma_toa_s: measurement noise standard deviations; gate: χ² innovation
    gate per RRH at ``gate_prob``. Distance-dependent W [ours, an option]: with
    ``distance_edges_m`` (increasing 2-D train–RRH distances [m]) the standard deviations of
    a measurement are those of its distance bin, ``sigma_aod_bins_rad`` and
    ``sigma_toa_bins_s`` (one more entry than edges), at the predicted distance. The AOD's
    error by departure angle [ours, an option; :mod:`railradio.nr.tracking.aod_model`]: with
    ``aod_angle_edges_rad`` (increasing angles from endfire [rad]) each AOD is predicted with
    its bin's bias toward broadside, ``aod_bias_bins_rad``, and weighted by its bin's σ,
    ``sigma_aod_angle_bins_rad``, at the predicted azimuth; it replaces the distance bins' AOD σ.

    Attributes
    ----------
    measurements : str
        The measurement set: ``aod``, ``toa`` or ``aod_toa``
        (:data:`railradio.nr.tracking.measurement.MEASUREMENT_SETS`).
    q : float
        White-jerk intensity, m² s⁻⁵ (> 0).
    sigma_aod_rad : float
        AOD noise standard deviation, rad (> 0).
    sigma_toa_s : float
        TOA noise standard deviation, s (> 0).
    gate : bool
        Whether the χ² innovation gate is applied.
    gate_prob : float
        Probability of the χ² gate (1).
    distance_edges_m : tuple of float
        Positive, increasing 2-D distance bin edges, m (empty: no bins).
    sigma_aod_bins_rad, sigma_toa_bins_s : tuple of float
        Per-bin σ, rad and s: ``len(distance_edges_m) + 1`` positive values each.
    aod_angle_edges_rad : tuple of float
        Increasing angle-from-endfire bin edges inside (0, π/2), rad (empty: no AOD model).
    aod_bias_bins_rad, sigma_aod_angle_bins_rad : tuple of float
        Per angle bin, the AOD bias toward broadside [rad] and σ [rad, > 0]:
        ``len(aod_angle_edges_rad) + 1`` values each.
    start_speed_sigma_m_s : float
        σ of the initial speed, m/s (> 0).
    track_bound : bool
        Hold the train on the track y = 0 and estimate the along-track state only.

    Raises
    ------
    ValueError
        When ``measurements`` is unknown, a σ, q or ``start_speed_sigma_m_s`` is not > 0, the edges
        are not positive and increasing, or a bin tuple has the wrong length or a value ≤ 0.
    """

    measurements: str = "aod_toa"
    q: float = 1.0
    sigma_aod_rad: float = np.radians(1.0)
    sigma_toa_s: float = 1.0 / 245.76e6
    gate: bool = False
    gate_prob: float = 0.99
    distance_edges_m: tuple[float, ...] = ()
    sigma_aod_bins_rad: tuple[float, ...] = ()
    sigma_toa_bins_s: tuple[float, ...] = ()
    aod_angle_edges_rad: tuple[float, ...] = ()
    aod_bias_bins_rad: tuple[float, ...] = ()
    sigma_aod_angle_bins_rad: tuple[float, ...] = ()
    start_speed_sigma_m_s: float = 1.0
    """σ of the initial speed [m/s] about 0: 1 for a start from rest (the source's
    trajectory); large for a start at an unknown speed (the reproduction map's segment)."""
    track_bound: bool = False
    """The train held on its known straight track (the source's y = 0 taken literally): the
    lateral position, speed and acceleration are fixed at 0 — no initial covariance, no process
    noise — so the filter estimates the along-track x, v_x, a_x only (docs/model/nr.md §6)."""

    def __post_init__(self) -> None:
        if self.measurements not in MEASUREMENT_SETS:
            raise ValueError(f"measurements must be one of {sorted(MEASUREMENT_SETS)}, got {self.measurements!r}")
        for name in ("q", "sigma_aod_rad", "sigma_toa_s", "start_speed_sigma_m_s"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")
        nb = len(self.distance_edges_m) + 1
        if self.distance_edges_m:
            if np.any(np.diff(self.distance_edges_m) <= 0) or self.distance_edges_m[0] <= 0:
                raise ValueError(f"distance_edges_m must be positive and increasing, got {self.distance_edges_m!r}")
            for name in ("sigma_aod_bins_rad", "sigma_toa_bins_s"):
                v = getattr(self, name)
                if len(v) != nb or not all(x > 0 for x in v):
                    raise ValueError(f"{name} must hold {nb} positive values (one per distance bin), got {v!r}")
        if self.aod_angle_edges_rad:
            e = np.asarray(self.aod_angle_edges_rad, float)
            if np.any(np.diff(e) <= 0) or e[0] <= 0 or e[-1] >= np.pi / 2:
                raise ValueError(
                    f"aod_angle_edges_rad must increase inside (0, pi/2), got {self.aod_angle_edges_rad!r}"
                )
            na = e.size + 1
            if len(self.aod_bias_bins_rad) != na or not np.all(np.isfinite(self.aod_bias_bins_rad)):
                raise ValueError(f"aod_bias_bins_rad must hold {na} finite values, got {self.aod_bias_bins_rad!r}")
            if len(self.sigma_aod_angle_bins_rad) != na or not all(x > 0 for x in self.sigma_aod_angle_bins_rad):
                raise ValueError(
                    f"sigma_aod_angle_bins_rad must hold {na} positive values, got {self.sigma_aod_angle_bins_rad!r}"
                )

    def record(self) -> dict:
        """The calibrated quantities as stored in ``calibration.json``.

        Returns
        -------
        dict
            ``q`` [m² s⁻⁵], ``sigma_aod_rad`` [rad], ``sigma_toa_s`` [s], and with distance bins
            ``distance_edges_m`` [m], ``sigma_aod_bins_rad`` [rad], ``sigma_toa_bins_s`` [s] (lists);
            with the AOD model ``aod_angle_edges_rad``, ``aod_bias_bins_rad``,
            ``sigma_aod_angle_bins_rad`` [rad] (lists).
        """
        out = {"q": self.q, "sigma_aod_rad": self.sigma_aod_rad, "sigma_toa_s": self.sigma_toa_s}
        for group in (_DISTANCE_BINS, _ANGLE_BINS):
            if getattr(self, group[0]):
                out |= {k: list(getattr(self, k)) for k in group}
        return out

    @classmethod
    def from_record(cls, rec: dict, **kw) -> TrackerConfig:
        """Inverse of :meth:`record` (``kw``: measurements, gate, gate_prob, track_bound).

        Parameters
        ----------
        rec : dict
            A record of :meth:`record` (extra keys are ignored).
        **kw
            Further :class:`TrackerConfig` fields (``measurements``, ``gate``, ``gate_prob``,
            ``track_bound``).

        Returns
        -------
        TrackerConfig
            The tracker configuration.

        Raises
        ------
        ValueError
            As :class:`TrackerConfig`, for invalid values.
        """
        bins = {k: tuple(rec[k]) for k in (*_DISTANCE_BINS, *_ANGLE_BINS) if k in rec}
        return cls(q=rec["q"], sigma_aod_rad=rec["sigma_aod_rad"], sigma_toa_s=rec["sigma_toa_s"], **bins, **kw)

    def noise(self, n: int, dist_m: NDArray | None = None) -> NDArray[np.float64]:
        """The measurement noise covariance W of ``n`` RRHs' stacked measurements (the order of
        :meth:`pick`).

        Parameters
        ----------
        n : int
            Number of RRHs.
        dist_m : numpy.ndarray or None
            [n] predicted 2-D train–RRH distances, m: each RRH's σ is that of its distance bin
            (:meth:`variances`; the overall σ when there are no bins). None: the overall σ
            (``sigma_aod_rad``, ``sigma_toa_s``) for every RRH.

        Returns
        -------
        numpy.ndarray
            [n·per, n·per] diagonal W, per = the measurement set's components per RRH: AOD variances
            [rad²] and TOA variances [s²], per RRH in the order AOD then TOA.
        """
        if dist_m is None:
            return np.diag(np.tile(self._variances, n))
        return np.diag(self.variances(np.asarray(dist_m, float).reshape(n)).ravel())

    def variances(self, dist_m: NDArray, aod_pred_rad: NDArray | None = None) -> NDArray[np.float64]:
        """Measurement variances of RRHs at given 2-D distances: the diagonal of :meth:`noise`,
        for arrays of RRHs.

        Parameters
        ----------
        dist_m : numpy.ndarray
            [...] 2-D train–RRH distances, m (a distance on a bin edge belongs to the lower
            bin; unused without distance bins).
        aod_pred_rad : numpy.ndarray or None
            [...] predicted azimuths [rad], the AOD model's bins (needed with it only).

        Returns
        -------
        numpy.ndarray
            [..., per] variances, AOD [rad²] then TOA [s²] as the measurement set uses them: those of
            each distance's bin, or without bins the overall variances (a read-only
            broadcast view).
        """
        d = np.asarray(dist_m, float)
        use_aod, use_toa = MEASUREMENT_SETS[self.measurements]
        angle = use_aod and bool(self.aod_angle_edges_rad)
        if not self.distance_edges_m and not angle:  # one W: the same variances for every RRH
            return np.broadcast_to(self._variances, d.shape + self._variances.shape)
        if angle and aod_pred_rad is None:
            raise ValueError("aod_pred_rad is needed with the AOD model (aod_angle_edges_rad)")
        b = np.searchsorted(self.distance_edges_m, d) if self.distance_edges_m else None
        sig = []
        if use_aod:
            if angle:
                psi, _ = aod_model.endfire_angle(np.asarray(aod_pred_rad, float))
                a = np.asarray(self.sigma_aod_angle_bins_rad)[aod_model.bin_index(psi, self.aod_angle_edges_rad)]
            else:
                a = np.asarray(self.sigma_aod_bins_rad)[b] if b is not None else np.full(d.shape, self.sigma_aod_rad)
            sig.append(a)
        if use_toa:
            sig.append(np.asarray(self.sigma_toa_bins_s)[b] if b is not None else np.full(d.shape, self.sigma_toa_s))
        return np.stack(sig, axis=-1) ** 2

    def predict(self, dx: NDArray, dy: NDArray, dh_m: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The predicted measurements and their variances of RRHs at train-minus-RRH offsets
        ``dx``, ``dy`` [m]: h of source eq. 14 with, under the AOD model, each AOD's bias at
        its predicted azimuth (:func:`railradio.nr.tracking.aod_model.predicted_bias`).

        Parameters
        ----------
        dx, dy : numpy.ndarray
            [m] offsets along and across the track [m].
        dh_m : float
            Height difference between the RRHs and the train antenna [m].

        Returns
        -------
        tuple of numpy.ndarray
            [m, per] predicted AOD [rad] and TOA [s], and [m, per] their variances [rad², s²].
        """
        h = h_terms(dx, dy, dh_m, self.measurements)
        use_aod = MEASUREMENT_SETS[self.measurements][0]
        aod = np.arctan2(dy, dx) if use_aod else None
        var = self.variances(np.hypot(dx, dy), aod)
        if use_aod and self.aod_angle_edges_rad:
            h[..., 0] += aod_model.predicted_bias(aod, self.aod_angle_edges_rad, self.aod_bias_bins_rad)
        return h, var

    def hx(self, s: NDArray, rrh_xy: NDArray, dh_m: float) -> NDArray[np.float64]:
        """:func:`railradio.nr.tracking.measurement.hx` (state ``s`` [6], RRHs ``rrh_xy`` [n, 2] [m],
        height difference ``dh_m`` [m]) with the AOD model's bias (:meth:`predict`): [n·per]
        (rad, s), ordered as :meth:`pick`."""
        return self.predict(s[0] - rrh_xy[:, 0], s[1] - rrh_xy[:, 1], dh_m)[0].ravel()

    def noise_at(self, s: NDArray, rrh_xy: NDArray, dh_m: float) -> NDArray[np.float64]:
        """W [n·per, n·per] (rad², s²) of the RRHs ``rrh_xy`` [n, 2] [m] seen from state ``s``
        [6]: :meth:`noise` at their predicted distances and azimuths (:meth:`predict`)."""
        return np.diag(self.predict(s[0] - rrh_xy[:, 0], s[1] - rrh_xy[:, 1], dh_m)[1].ravel())

    @cached_property
    def _variances(self) -> NDArray[np.float64]:
        """The overall variances, without distance bins.

        Returns
        -------
        numpy.ndarray
            [per] ``sigma_aod_rad``² [rad²] then ``sigma_toa_s``² [s²], as the measurement set uses
            them (read-only).
        """
        use_aod, use_toa = MEASUREMENT_SETS[self.measurements]
        v = np.array(([self.sigma_aod_rad] if use_aod else []) + ([self.sigma_toa_s] if use_toa else [])) ** 2
        v.flags.writeable = False
        return v

    def pick(self, aod: NDArray, toa: NDArray) -> NDArray[np.float64]:
        """The measurement vector of the measurement set's components, in the order of :meth:`noise`.

        Parameters
        ----------
        aod : numpy.ndarray
            [m] measured AODs of m RRHs, rad.
        toa : numpy.ndarray
            [m] their measured TOAs, s.

        Returns
        -------
        numpy.ndarray
            [m·per] ``[aod_0, toa_0, aod_1, toa_1, ...]`` (rad, s) for ``aod_toa``; the AODs
            [rad] alone for ``aod``; the TOAs [s] alone for ``toa`` (a new array).
        """
        use_aod, use_toa = MEASUREMENT_SETS[self.measurements]
        if not use_aod:
            return np.array(toa, dtype=float).ravel()
        if not use_toa:
            return np.array(aod, dtype=float).ravel()
        out = np.empty(2 * np.size(aod))
        out[0::2], out[1::2] = aod, toa
        return out


def run_ekf(
    select: Select,
    dt_s: float,
    dh_m: float,
    cfg: TrackerConfig,
    s0: NDArray,
    p0: NDArray,
    n_epochs: int,
    reacquire: Reacquire | None = None,
    reacquire_after: int = 10,
) -> dict[str, NDArray]:
    """Run the EKF over ``n_epochs`` epochs; ``select(n, x_pred) -> (rrh_xy, aod, toa)`` chooses the measurements
    of epoch n from the predicted state: from the RRHs ``rrh_xy`` [m_n, 2] (possibly none: prediction only).
    With the gate on, ``reacquire(n) -> (position [2], covariance [2, 2]) | None`` re-initialises the position after
    ``reacquire_after`` consecutive epochs whose measurements were all rejected (track loss: a gate alone never
    lets a lost filter back) [ours].

    Parameters
    ----------
    select : Select
        The measurements of each epoch: RRH positions [m], AODs [rad], TOAs [s] (:data:`Select`).
    dt_s, dh_m : float
        Epoch interval [s]; height difference between the RRHs and the train antenna [m].
    cfg : TrackerConfig
        Measurement set, q, W and gate.
    s0, p0 : numpy.ndarray
        Initial state [6] (x, y [m], v_x, v_y [m/s], a_x, a_y [m/s²]) and its covariance [6, 6].
    n_epochs, reacquire_after : int
        Epochs to run; consecutive all-rejected epochs before ``reacquire`` is called.
    reacquire : Reacquire or None
        The re-acquisition fix: position [2] [m], covariance [2, 2] [m²]; None: never re-acquires.

    Returns
    -------
    dict of str to numpy.ndarray
        ``state`` [n, 6] (posterior, units as ``s0``), ``cov`` [n, 6, 6], ``nis`` [n] [1] (NaN without
        measurements), ``n_used`` [n] (RRHs used after gating), ``reacquired`` [n] (bool).
    """
    f = transition(dt_s)
    ekf = ExtendedKalmanFilter(dim_x=6, dim_z=1)
    ekf.x = np.asarray(s0, float).copy()
    ekf.P = np.asarray(p0, float).copy()
    ekf.F = f
    ekf.Q = process_noise(dt_s, cfg.q)
    if cfg.track_bound:  # y, v_y, a_y held at 0: no covariance, no process noise (so no gain)
        ekf.x[LATERAL] = 0.0
        for m in (ekf.P, ekf.Q):
            m[LATERAL, :] = 0.0
            m[:, LATERAL] = 0.0
    res = residual_fn(cfg.measurements)
    per = sum(MEASUREMENT_SETS[cfg.measurements])
    n = n_epochs
    states = np.zeros((n, 6))
    covs = np.zeros((n, 6, 6))
    nis = np.full(n, np.nan)
    used = np.zeros(n, dtype=np.int64)
    gate = chi2.ppf(cfg.gate_prob, per) if cfg.gate else np.inf
    misses = 0
    reacquired = np.zeros(n, dtype=bool)
    for k in range(n):
        if k > 0:
            ekf.predict()
        xy, aod_k, toa_k = select(k, ekf.x)
        xy = np.asarray(xy, float).reshape(-1, 2)
        if xy.shape[0]:
            z = cfg.pick(np.asarray(aod_k), np.asarray(toa_k))
            n_used = _gated_update(ekf, xy, z, dh_m, cfg, res, gate)
            if n_used:
                nis[k] = float(ekf.y @ np.linalg.solve(ekf.S, ekf.y))
                used[k] = n_used
                misses = 0
            else:
                misses += 1
                if reacquire is not None and misses >= reacquire_after:
                    fix = reacquire(k)
                    if fix is not None:
                        pos = [0] if cfg.track_bound else [0, 1]  # on the track: the fix's x alone
                        ekf.x[pos] = np.asarray(fix[0])[pos]
                        ekf.P[pos, :] = 0.0
                        ekf.P[:, pos] = 0.0
                        ekf.P[np.ix_(pos, pos)] = np.asarray(fix[1])[np.ix_(pos, pos)]
                        reacquired[k] = True
                        misses = 0
        states[k] = ekf.x
        covs[k] = ekf.P
    return {"state": states, "cov": covs, "nis": nis, "n_used": used, "reacquired": reacquired}


def _gated_update(
    ekf: ExtendedKalmanFilter, xy: NDArray, z: NDArray, dh_m: float, cfg: TrackerConfig, res, gate: float
) -> int:
    """EKF update of ``ekf`` with the measurements of the RRHs that pass the χ² gate (with
    ``cfg.gate``; without it every RRH is used).

    Parameters
    ----------
    ekf : filterpy.kalman.ExtendedKalmanFilter
        The filter after its prediction; updated in place.
    xy : numpy.ndarray
        [m, 2] positions (x, y) of the measured RRHs, m.
    z : numpy.ndarray
        [m·per] their measurements (:meth:`TrackerConfig.pick`: rad, s).
    dh_m : float
        Height difference between the RRHs and the train antenna, m.
    cfg : TrackerConfig
        Measurement set, W and whether the gate is on.
    res : callable
        The measurement set's residual (:func:`railradio.nr.tracking.measurement.residual_fn`).
    gate : float
        χ² threshold of each RRH's squared innovation distance (1).

    Returns
    -------
    int
        How many RRHs the update used (0: all rejected, no update).
    """
    per = sum(MEASUREMENT_SETS[cfg.measurements])
    m_k = xy.shape[0]
    # h, ∂h/∂s and the RRH distances at the prediction, once for the gate and the
    # update (filterpy evaluates them at the same ekf.x: the kept RRHs' rows)
    dx, dy = ekf.x[0] - xy[:, 0], ekf.x[1] - xy[:, 1]
    h_all = np.zeros((m_k, per, 6))
    h_all[..., :2] = jac_terms(dx, dy, dh_m, cfg.measurements)
    hx_all, var_all = cfg.predict(dx, dy, dh_m)  # [m_k, per] each
    keep = np.ones(m_k, dtype=bool)
    if cfg.gate:  # per-RRH χ² test on the predicted innovation (all RRHs at once)
        s_i = np.einsum("ipa,ab,iqb->ipq", h_all, ekf.P, h_all)  # H_i P H_iᵀ
        s_i[:, np.arange(per), np.arange(per)] += var_all
        r_i = res(z, hx_all.ravel()).reshape(m_k, per)
        d2 = np.einsum("ip,ip->i", r_i, np.linalg.solve(s_i, r_i[..., None])[..., 0])
        keep = d2 <= gate
    if not keep.any():
        return 0
    if not keep.all():
        h_all, hx_all, var_all, z = h_all[keep], hx_all[keep], var_all[keep], z[np.repeat(keep, per)]
    h_k, hx_k = h_all.reshape(-1, 6), hx_all.ravel()
    ekf.update(z, lambda s, h=h_k: h, lambda s, hx=hx_k: hx, R=np.diag(var_all.ravel()), residual=res)
    return int(keep.sum())


def nees_position(state: NDArray, cov: NDArray, x_true: NDArray, track_bound: bool = False) -> NDArray[np.float64]:
    """Normalized estimation error squared of the 2-D position, eᵀ P_pos⁻¹ e per epoch
    (e = estimate − truth, the train at y = 0); χ²₂-distributed for a consistent filter
    (mean 2). For a track-bound filter (``track_bound``: y held at 0) the along-track
    e_x² / P_xx, χ²₁-distributed (mean 1). NaN before the track starts. Scoring only: it
    uses the truth.

    Parameters
    ----------
    state : numpy.ndarray
        [epoch, 6] tracker states (x, y first, m).
    cov : numpy.ndarray
        [epoch, 6, 6] their covariances (position block in m²).
    x_true : numpy.ndarray
        [epoch] true along-track positions, m.
    track_bound : bool
        The filter held y at 0 (:attr:`TrackerConfig.track_bound`).

    Returns
    -------
    numpy.ndarray
        [epoch] position NEES (1); NaN where undefined.
    """
    if track_bound:
        with np.errstate(invalid="ignore", divide="ignore"):
            q = (state[:, 0] - np.asarray(x_true, float)) ** 2 / cov[:, 0, 0]
        return np.where(np.isfinite(q), q, np.nan)
    e = np.stack([state[:, 0] - np.asarray(x_true, float), state[:, 1]], axis=1)
    p = cov[:, :2, :2]
    det = p[:, 0, 0] * p[:, 1, 1] - p[:, 0, 1] * p[:, 1, 0]
    with np.errstate(invalid="ignore", divide="ignore"):
        q = (p[:, 1, 1] * e[:, 0] ** 2 - 2 * p[:, 0, 1] * e[:, 0] * e[:, 1] + p[:, 0, 0] * e[:, 1] ** 2) / det
    return np.where(np.isfinite(q), q, np.nan)
