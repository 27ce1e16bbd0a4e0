"""EKF tracking of the train from per-RRH AOD/TOA measurements (seed eq. 10–14).

The motion model (:mod:`railradio.nr.dynamics`, seed eq. 10–12) and the measurement model
(:mod:`railradio.nr.measurement`, seed eq. 13–14) in an extended Kalman filter:
filterpy's ExtendedKalmanFilter does the algebra; a χ² gate per RRH is an option. The
tracker picks its measurements from the predicted position, starts from a snapshot fix
(:mod:`railradio.nr.snapshot`) and re-acquires a lost track from one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter
from numpy.typing import NDArray
from scipy.stats import chi2

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.antenna import facing_panel
from railradio.nr.dynamics import process_noise, transition
from railradio.nr.measurement import VARIANTS, h_terms, jac_terms, residual_fn
from railradio.nr.snapshot import snapshot_ls, snapshot_ls_batch

Select = Callable[[int, NDArray], tuple[NDArray, NDArray, NDArray]]
"""``select(n, x_pred) -> (rrh_xy [m_n, 2], aod [m_n], toa [m_n])``: the measurements of
epoch n, chosen from the predicted state ``x_pred`` [6]."""
Reacquire = Callable[[int], tuple[NDArray, NDArray] | None]
"""``reacquire(n) -> (position [2], covariance [2, 2]) | None``: a position fix at epoch n."""


@dataclass(frozen=True)
class TrackerConfig:
    """Tracker settings [ours unless noted].

    variant: ``aod``, ``toa`` or ``aod_toa`` [seed]; q: white-jerk intensity [m² s⁻⁵];
    sigma_aod_rad, sigma_toa_s: measurement noise standard deviations; gate: χ² innovation
    gate per RRH at ``gate_prob``. Distance-dependent W [ours, an option]: with
    ``distance_edges_m`` (increasing 2-D train–RRH distances [m]) the standard deviations of
    a measurement are those of its distance bin, ``sigma_aod_bins_rad`` and
    ``sigma_toa_bins_s`` (one more entry than edges), at the predicted distance.

    Attributes
    ----------
    variant : str
        ``aod``, ``toa`` or ``aod_toa``.
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
    start_speed_sigma_m_s : float
        σ of the initial speed, m/s (> 0).

    Raises
    ------
    ValueError
        When ``variant`` is unknown, a σ, q or ``start_speed_sigma_m_s`` is not > 0, the edges
        are not positive and increasing, or a bin tuple has the wrong length or a value ≤ 0.
    """

    variant: str = "aod_toa"
    q: float = 1.0
    sigma_aod_rad: float = np.radians(1.0)
    sigma_toa_s: float = 1.0 / 245.76e6
    gate: bool = False
    gate_prob: float = 0.99
    distance_edges_m: tuple[float, ...] = ()
    sigma_aod_bins_rad: tuple[float, ...] = ()
    sigma_toa_bins_s: tuple[float, ...] = ()
    start_speed_sigma_m_s: float = 1.0
    """σ of the initial speed [m/s] about 0: 1 for a start from rest (the seed's
    trajectory); large for a start at an unknown speed (the reproduction map's segment)."""

    def __post_init__(self) -> None:
        if self.variant not in VARIANTS:
            raise ValueError(f"variant must be one of {sorted(VARIANTS)}, got {self.variant!r}")
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

    def record(self) -> dict:
        """The calibrated quantities as stored in ``calibration.json``.

        Returns
        -------
        dict
            ``q`` [m² s⁻⁵], ``sigma_aod_rad`` [rad], ``sigma_toa_s`` [s], and with distance bins
            ``distance_edges_m`` [m], ``sigma_aod_bins_rad`` [rad], ``sigma_toa_bins_s`` [s] (lists).
        """
        out = {"q": self.q, "sigma_aod_rad": self.sigma_aod_rad, "sigma_toa_s": self.sigma_toa_s}
        if self.distance_edges_m:
            out |= {
                "distance_edges_m": list(self.distance_edges_m),
                "sigma_aod_bins_rad": list(self.sigma_aod_bins_rad),
                "sigma_toa_bins_s": list(self.sigma_toa_bins_s),
            }
        return out

    @classmethod
    def from_record(cls, rec: dict, **kw) -> TrackerConfig:
        """Inverse of :meth:`record` (``kw``: variant, gate, gate_prob).

        Parameters
        ----------
        rec : dict
            A record of :meth:`record` (extra keys are ignored).
        **kw
            Further :class:`TrackerConfig` fields (``variant``, ``gate``, ``gate_prob``).

        Returns
        -------
        TrackerConfig
            The tracker configuration.

        Raises
        ------
        ValueError
            As :class:`TrackerConfig`, for invalid values.
        """
        bins = {k: tuple(rec[k]) for k in ("distance_edges_m", "sigma_aod_bins_rad", "sigma_toa_bins_s") if k in rec}
        return cls(q=rec["q"], sigma_aod_rad=rec["sigma_aod_rad"], sigma_toa_s=rec["sigma_toa_s"], **bins, **kw)

    def noise(self, n: int, dist_m: NDArray | None = None) -> NDArray[np.float64]:
        """W for ``n`` RRHs; ``dist_m`` [n] their predicted 2-D distances [m] (used only
        with distance bins; without them the overall σ)."""
        if dist_m is None:
            return np.diag(np.tile(self._variances, n))
        return np.diag(self.variances(np.asarray(dist_m, float).reshape(n)).ravel())

    def variances(self, dist_m: NDArray) -> NDArray[np.float64]:
        """Measurement variances [..., per] (AOD [rad²] then TOA [s²], as used by the
        variant) of RRHs at 2-D distances ``dist_m`` [...] [m]: the diagonal of
        :meth:`noise`, for arrays of RRHs."""
        d = np.asarray(dist_m, float)
        if not self.distance_edges_m:  # one W: the same variances for every RRH
            return np.broadcast_to(self._variances, d.shape + self._variances.shape)
        use_aod, use_toa = VARIANTS[self.variant]
        b = np.searchsorted(self.distance_edges_m, d)
        sig = ([np.asarray(self.sigma_aod_bins_rad)[b]] if use_aod else []) + (
            [np.asarray(self.sigma_toa_bins_s)[b]] if use_toa else []
        )
        return np.stack(sig, axis=-1) ** 2

    @cached_property
    def _variances(self) -> NDArray[np.float64]:
        """The overall variances [per] (no distance bins)."""
        use_aod, use_toa = VARIANTS[self.variant]
        v = np.array(([self.sigma_aod_rad] if use_aod else []) + ([self.sigma_toa_s] if use_toa else [])) ** 2
        v.flags.writeable = False
        return v

    def pick(self, aod: NDArray, toa: NDArray) -> NDArray[np.float64]:
        """The measurement vector [aod_0, toa_0, aod_1, ...] of the variant's components."""
        use_aod, use_toa = VARIANTS[self.variant]
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
    With the gate on, ``reacquire(n) -> (position [2], covariance [2, 2]) | None`` re-seeds the position after
    ``reacquire_after`` consecutive epochs whose measurements were all rejected (track loss: a gate alone never
    lets a lost filter back) [ours].

    Parameters
    ----------
    select : Select
        The measurements of each epoch: RRH positions [m], AODs [rad], TOAs [s] (:data:`Select`).
    dt_s, dh_m : float
        Epoch interval [s]; height difference between the RRHs and the train antenna [m].
    cfg : TrackerConfig
        Variant, q, W and gate.
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
    res = residual_fn(cfg.variant)
    per = sum(VARIANTS[cfg.variant])
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
                        ekf.x[:2] = fix[0]
                        ekf.P[:2, :] = 0.0
                        ekf.P[:, :2] = 0.0
                        ekf.P[:2, :2] = fix[1]
                        reacquired[k] = True
                        misses = 0
        states[k] = ekf.x
        covs[k] = ekf.P
    return {"state": states, "cov": covs, "nis": nis, "n_used": used, "reacquired": reacquired}


def _gated_update(
    ekf: ExtendedKalmanFilter, xy: NDArray, z: NDArray, dh_m: float, cfg: TrackerConfig, res, gate: float
) -> int:
    """EKF update of ``ekf`` with the measurements ``z`` of the RRHs ``xy`` [m, 2] that pass
    the χ² gate at threshold ``gate`` (with ``cfg.gate``); returns how many RRHs it used
    (0: all rejected, no update). ``res``: the variant's residual (:func:`residual_fn`)."""
    per = sum(VARIANTS[cfg.variant])
    m_k = xy.shape[0]
    # h, ∂h/∂s and the RRH distances at the prediction, once for the gate and the
    # update (filterpy evaluates them at the same ekf.x: the kept RRHs' rows)
    dx, dy = ekf.x[0] - xy[:, 0], ekf.x[1] - xy[:, 1]
    h_all = np.zeros((m_k, per, 6))
    h_all[..., :2] = jac_terms(dx, dy, dh_m, cfg.variant)
    hx_all = h_terms(dx, dy, dh_m, cfg.variant)  # [m_k, per]
    var_all = cfg.variances(np.hypot(dx, dy))  # [m_k, per]
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


def anchor_x(cand_rrh: NDArray, cand_ok: NDArray, cand_strength: NDArray, rrh_x: NDArray) -> float:
    """Along-track position [m] of the strongest cell with a measurement (AOD and TOA) among
    an epoch's candidates: where a receiver without a track places itself (the snapshot
    fix, the EKF's start); it sees only its measurements and the deployment, no truth.
    NaN when nothing was measured."""
    if not cand_ok.any():
        return float("nan")
    j = int(np.argmax(np.where(cand_ok, cand_strength, -np.inf)))
    return float(rrh_x[cand_rrh[j]])


def select_measurements(
    cand_rrh: NDArray,
    cand_ok: NDArray,
    cand_strength: NDArray,
    rrh_x: NDArray,
    x_pred: float,
    n_nearest: int = 6,
    n_use: int = 3,
) -> NDArray[np.int64]:
    """Candidate columns to use at one epoch: among the detected candidates that are also
    among the ``n_nearest`` RRHs to the predicted position, the ``n_use`` strongest
    (seed §4: the 3 strongest of the audible RRHs) [ours: the nearest-to-prediction rule].
    ``rrh_x``: the RRH positions along the track, increasing [m]."""
    if abs(x_pred) < 1e9:  # rrh_x increasing: the n nearest lie within n places of x_pred's
        # insertion point (the same set and tie-breaking as a stable argsort over all RRHs)
        i = int(np.searchsorted(rrh_x, x_pred))
        lo = max(i - n_nearest, 0)
        win = np.abs(rrh_x[lo : i + n_nearest] - x_pred)
        near = lo + np.argsort(win, kind="stable")[:n_nearest]
    else:  # a lost filter (far off, or NaN): the order rounding gives over all RRHs
        near = np.argsort(np.abs(rrh_x - x_pred), kind="stable")[:n_nearest]
    cols = np.flatnonzero(cand_ok & (cand_rrh[:, None] == near[None, :]).any(axis=1))
    # strongest first; equal strengths keep the candidate order
    return cols[np.argsort(-cand_strength[cols], kind="stable")[:n_use]].astype(np.int64)


@dataclass(frozen=True, eq=False)
class MeasuredCandidates:
    """One realization's candidates [epoch, cand] as the tracker sees them, and how it picks
    its measurements from them and fixes its position (no truth).

    ``rrh``: the candidates' RRH ids; ``aod`` [rad], ``toa`` [s]: their estimates; ``ok``:
    both measured; ``strength``: the selection strength (-inf where none); ``rrh_x``: the
    RRH positions along the track, increasing [m]; ``rrh_y`` [m]: their offset; ``dh_m``:
    the height difference [m]; ``cfg``: the tracker; ``n_use``: RRHs used per epoch;
    ``panel_x``: the along-track lever arms ℓ [m] of the head/tail panels ((0, 0): the
    point model).
    """

    rrh: NDArray[np.int64]
    aod: NDArray[np.float64]
    toa: NDArray[np.float64]
    ok: NDArray[np.bool_]
    strength: NDArray[np.float64]
    rrh_x: NDArray[np.float64]
    rrh_y: float
    dh_m: float
    cfg: TrackerConfig
    n_use: int
    panel_x: tuple[float, float]

    @property
    def n_epochs(self) -> int:
        """Number of epochs (rows of the candidate arrays)."""
        return self.rrh.shape[0]

    def pick(self, k: int, x_pred: float) -> tuple[NDArray, NDArray, NDArray]:
        """Measurement selection at epoch ``k`` around the predicted along-track position
        ``x_pred`` [m] (:func:`select_measurements`): the RRHs [m, 2] (each shifted by the
        lever arm of the panel facing it), their AODs and TOAs."""
        cols = select_measurements(
            self.rrh[k], self.ok[k], self.strength[k], self.rrh_x, x_pred, self.rrh.shape[1], self.n_use
        )
        x_k = self.rrh_x[self.rrh[k, cols]]
        if self.panel_x != (0.0, 0.0):  # lever arm of the panel facing each RRH
            x_k = x_k - np.asarray(self.panel_x)[facing_panel(x_pred, x_k, self.rrh_y, self.panel_x)]
        xy = np.stack([x_k, np.full(cols.size, self.rrh_y)], axis=1) if cols.size else np.zeros((0, 2))
        return xy, self.aod[k, cols], self.toa[k, cols]

    def snapshot_fix(self, k: int, x_pred: float) -> tuple[NDArray, NDArray] | None:
        """LS fix from the measurements picked around ``x_pred``, started at the strongest
        one's own closed form x_k + ρ (cos θ, sin θ) (ρ the horizontal range); None when
        nothing is measured or the LS runs away (farther from that RRH than its measured
        range plus 1 km)."""
        xy, a_k, t_k = self.pick(k, x_pred)
        if xy.shape[0] == 0:
            return None
        rho = np.sqrt(max((SPEED_OF_LIGHT_M_S * t_k[0]) ** 2 - self.dh_m**2, 1.0))
        guess = np.array([xy[0, 0] + rho * np.cos(a_k[0]), xy[0, 1] + rho * np.sin(a_k[0])])
        fix, cov = snapshot_ls(xy, a_k, t_k, self.dh_m, self.cfg, guess)
        if not (np.all(np.isfinite(fix)) and np.all(np.isfinite(cov)) and np.hypot(*(fix - xy[0])) <= rho + 1000.0):
            return None
        return fix, cov

    def snapshot_fixes(self) -> NDArray[np.float64]:
        """Snapshot LS fix [epoch, 2] of every epoch (NaN where nothing was measured): no
        tracking; each epoch's measurements are those around its strongest measured cell,
        and each fix starts from that cell's own AOD/TOA closed form x_k + ρ cos θ (ρ the
        horizontal range)."""
        n, n_use = self.n_epochs, self.n_use
        snap = np.full((n, 2), np.nan)
        xy_all = np.full((n, n_use, 2), np.nan)
        a_all = np.full((n, n_use), np.nan)
        t_all = np.full((n, n_use), np.nan)
        for k in range(n):
            if not self.ok[k].any():
                continue
            xy, a_k, t_k = self.pick(k, anchor_x(self.rrh[k], self.ok[k], self.strength[k], self.rrh_x))
            j = xy.shape[0]
            xy_all[k, :j], a_all[k, :j], t_all[k, :j] = xy, a_k, t_k
        has = np.isfinite(xy_all[:, 0, 0])
        if has.any():
            xy0, a0, t0 = xy_all[has, 0], a_all[has, 0], t_all[has, 0]
            rho = np.sqrt(np.maximum((SPEED_OF_LIGHT_M_S * t0) ** 2 - self.dh_m**2, 1.0))
            guess = np.stack([xy0[:, 0] + rho * np.cos(a0), xy0[:, 1] + rho * np.sin(a0)], axis=1)
            snap[has], _ = snapshot_ls_batch(xy_all[has], a_all[has], t_all[has], self.dh_m, self.cfg, guess)
        return snap


@dataclass(frozen=True, eq=False)
class TrackSetup:
    """What :func:`track_setup` gives: the measured candidates ``meas``, the first epoch with
    measurements ``k0``, the initial state ``s0`` [6] and its covariance ``p0`` [6, 6]."""

    meas: MeasuredCandidates
    k0: int
    s0: NDArray[np.float64]
    p0: NDArray[np.float64]

    @property
    def n_epochs(self) -> int:
        return self.meas.n_epochs

    def follower(self) -> _Follower:
        """A fresh ``select``/``reacquire`` pair for one filter run from ``k0`` on."""
        return _Follower(self)


class _Follower:
    """``select`` and ``reacquire`` of one filter run from epoch k0 on (:func:`run_ekf`, the
    IMM): the measurements picked around the predicted along-track position; with the gate
    on, the snapshot fix around the last such position."""

    def __init__(self, setup: TrackSetup) -> None:
        self._setup = setup
        self._x = setup.s0[0]

    def select(self, k: int, s: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        self._x = float(s[0])
        return self._setup.meas.pick(k + self._setup.k0, float(s[0]))

    def reacquire(self, k: int) -> tuple[NDArray, NDArray] | None:
        meas = self._setup.meas
        return meas.snapshot_fix(k + self._setup.k0, self._x) if meas.cfg.gate else None


def track_setup(
    ds, rrh_x: NDArray, rrh_y: float, dh_m: float, cfg: TrackerConfig, strength: str, n_use: int, lever_arm: bool = True
) -> TrackSetup:
    """Measurement selection (:meth:`MeasuredCandidates.pick`), the snapshot re-acquisition fix
    (:meth:`MeasuredCandidates.snapshot_fix`), the first epoch with measurements k0, the initial state and P0 (snapshot
    LS position at rest; σ of v_x ``cfg.start_speed_sigma_m_s``, of v_y 1 m/s, of the accelerations 1 m/s² [ours])
    and the number of epochs: the set-up shared by :func:`track` and the IMM.

    Separate head/tail panels (``ds["train_panel_x"]`` nonzero): each measurement is taken at the panel facing
    its RRH at the predicted position (:func:`railradio.nr.antenna.facing_panel`), whose along-track lever arm ℓ
    enters h(x) as an RRH shifted by -ℓ (on the straight track, x + ℓ - x_k = x - (x_k - ℓ); the Jacobian is
    unchanged). ``lever_arm=False`` ignores it: the seed's point model [ours].

    Parameters
    ----------
    ds, rrh_x, rrh_y, dh_m, cfg, strength, n_use, lever_arm
        As for :func:`track` (estimates [rad], [s]; RRH positions [n_rrh], offset, height difference [m]).

    Returns
    -------
    TrackSetup
        ``meas``, ``k0``, ``s0`` [6] (x, y [m], speed and acceleration 0) and ``p0`` [6, 6] (SI units squared).
    """
    panel_x = tuple(float(v) for v in ds["train_panel_x"].values) if lever_arm and "train_panel_x" in ds else (0.0, 0.0)
    rrh = ds["rrh"].values
    aod = ds["aod_hat"].values
    toa = ds["toa_hat"].values
    ok = np.isfinite(aod) & np.isfinite(toa)
    stren = np.nan_to_num(ds[strength].values, nan=-np.inf)
    meas = MeasuredCandidates(rrh, aod, toa, ok, stren, rrh_x, rrh_y, dh_m, cfg, n_use, panel_x)

    # the start: the first epoch whose strongest measured cell gives a fix (no truth)
    k0, start = 0, None
    for k in np.flatnonzero(ok.any(axis=1)):
        start = meas.snapshot_fix(int(k), anchor_x(rrh[k], ok[k], stren[k], rrh_x))
        if start is not None:
            k0 = int(k)
            break
    if start is None:  # nothing measured anywhere: the filter starts at the first RRH, uninformed
        start = (np.array([rrh_x[0], 0.0]), np.eye(2) * 1e12)
    p_fix, cov = start
    s0 = np.array([p_fix[0], p_fix[1], 0.0, 0.0, 0.0, 0.0])
    sv2 = cfg.start_speed_sigma_m_s**2
    p0 = np.diag([cov[0, 0], cov[1, 1], sv2, 1.0, 1.0, 1.0])
    p0[0, 1] = p0[1, 0] = cov[0, 1]

    return TrackSetup(meas, k0, s0, p0)


def track(
    ds,
    rrh_x: NDArray,
    rrh_y: float,
    dh_m: float,
    dt_s: float,
    cfg: TrackerConfig,
    strength: str = "peak",
    n_use: int = 3,
    snapshot: bool = True,
    lever_arm: bool = True,
) -> dict[str, NDArray]:
    """Track one realization from a :func:`railradio.nr.simulate.simulate_epochs` dataset.

    The first epoch with measurements gives the initial state (snapshot LS position, at
    rest: the seed's trajectory starts from standstill) and P0 (its covariance; speed and
    acceleration standard deviations 1 m/s and 1 m/s² [ours]). Also returns (``snapshot``) the snapshot
    LS fix of every epoch (no tracking) as a baseline.

    Parameters
    ----------
    ds : xarray.Dataset
        One receiver's estimates (a :func:`railradio.nr.simulate.simulate_epochs` dataset
        selected at one ``receiver``): ``aod_hat`` [rad], ``toa_hat`` [s], their truths
        ``aod_true``, ``toa_true``, and the strength variables, dims (``epoch``, ``cand``).
        Also ``rrh`` (candidate RRH indices) and, for the panels' lever arm, ``train_panel_x`` [m].
    rrh_x : numpy.ndarray
        Along-track positions of the RRHs, m (``Deployment.x_m``).
    rrh_y : float
        Lateral offset of the RRHs from the track, m (``Deployment.offset_m``).
    dh_m : float
        RRH height above the train antenna, m (``h_bs_m - h_ut_m``).
    dt_s : float
        Epoch interval, s.
    cfg : TrackerConfig
        The tracker settings (variant, q, W, gate).
    strength : str
        Variable ranking the candidates (the receiver's selection): ``"peak"`` (combined
        correlation peak), ``"ss_rsrp"`` or ``"best_score"``.
    n_use : int
        Strongest measured candidates used per epoch.
    snapshot : bool
        Also compute the per-epoch snapshot LS fix.
    lever_arm : bool
        Model the head/tail panels' along-track lever arm (False: the seed's point model).

    Returns
    -------
    dict
        ``state`` [epoch, 6] (x, y [m], v_x, v_y [m/s], a_x, a_y [m/s²]; NaN before ``k0``),
        ``cov`` [epoch, 6, 6] (its covariance, SI units squared), ``nis`` [epoch] (1), ``n_used``
        [epoch] (RRHs used per update), ``snapshot`` [epoch, 2] (x, y [m]; NaN without
        ``snapshot``), ``k0`` (int, first tracked epoch), ``reacquired`` [epoch] (bool).
    """
    setup = track_setup(ds, rrh_x, rrh_y, dh_m, cfg, strength, n_use, lever_arm)
    k0, n = setup.k0, setup.n_epochs
    follow = setup.follower()
    out = run_ekf(follow.select, dt_s, dh_m, cfg, setup.s0, setup.p0, n - k0, reacquire=follow.reacquire)
    state = np.full((n, 6), np.nan)
    state[k0:] = out["state"]
    cov = np.full((n, 6, 6), np.nan)
    cov[k0:] = out["cov"]
    nis = np.full(n, np.nan)
    nis[k0:] = out["nis"]
    used = np.zeros(n, dtype=np.int64)
    used[k0:] = out["n_used"]
    # snapshot LS baseline (no tracking, MeasuredCandidates.snapshot_fixes)
    snap = setup.meas.snapshot_fixes() if snapshot else np.full((n, 2), np.nan)
    reac = np.zeros(n, dtype=bool)
    reac[k0:] = out["reacquired"]
    return {"state": state, "cov": cov, "nis": nis, "n_used": used, "snapshot": snap, "k0": k0, "reacquired": reac}


def nees_position(state: NDArray, cov: NDArray, x_true: NDArray) -> NDArray[np.float64]:
    """Normalized estimation error squared of the 2-D position, eᵀ P_pos⁻¹ e per epoch
    (e = estimate − truth, the train at y = 0); χ²₂-distributed for a consistent filter
    (mean 2). NaN before the track starts. Scoring only: it uses the truth.

    Parameters
    ----------
    state : numpy.ndarray
        [epoch, 6] tracker states (x, y first, m).
    cov : numpy.ndarray
        [epoch, 6, 6] their covariances (position block in m²).
    x_true : numpy.ndarray
        [epoch] true along-track positions, m.

    Returns
    -------
    numpy.ndarray
        [epoch] position NEES (1); NaN where undefined.
    """
    e = np.stack([state[:, 0] - np.asarray(x_true, float), state[:, 1]], axis=1)
    p = cov[:, :2, :2]
    det = p[:, 0, 0] * p[:, 1, 1] - p[:, 0, 1] * p[:, 1, 0]
    with np.errstate(invalid="ignore", divide="ignore"):
        q = (p[:, 1, 1] * e[:, 0] ** 2 - 2 * p[:, 0, 1] * e[:, 0] * e[:, 1] + p[:, 0, 0] * e[:, 1] ** 2) / det
    return np.where(np.isfinite(q), q, np.nan)
