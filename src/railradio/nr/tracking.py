"""EKF tracking of the train from per-RRH AOD/TOA measurements (seed eq. 10–14).

State s = [x, y, v_x, v_y, a_x, a_y] (seed eq. 10), constant-acceleration transition
(seed eq. 11–12) with white-jerk process noise of intensity q [m² s⁻⁵] [ours]; per measured
RRH k, h_k(s) = [atan2(y - y_k, x - x_k), ‖p - p_k‖/c] (seed eq. 14) with the 3-D range
(known height difference). The innovation is y - h(ŝ⁻) (the seed's eq. 13 misprints a
plus); angle innovations are wrapped to (-π, π]. filterpy's ExtendedKalmanFilter does the
algebra; a χ² gate per RRH is an option.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter
from numpy.typing import NDArray
from scipy.stats import chi2

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.antenna import wrap_rad

VARIANTS = {"aod": (True, False), "toa": (False, True), "aod_toa": (True, True)}
"""Measurement variants: which of (AOD, TOA) each RRH contributes (seed §4)."""


def transition(dt_s: float) -> NDArray[np.float64]:
    """Constant-acceleration F for s = [x, y, vx, vy, ax, ay]."""
    f1 = np.array([[1.0, dt_s, 0.5 * dt_s**2], [0.0, 1.0, dt_s], [0.0, 0.0, 1.0]])
    return _interleave(f1)


def process_noise(dt_s: float, q: float) -> NDArray[np.float64]:
    """White-jerk process noise: per axis q·[[T⁵/20, T⁴/8, T³/6], [T⁴/8, T³/3, T²/2], [T³/6, T²/2, T]]."""
    t = dt_s
    q1 = q * np.array([[t**5 / 20, t**4 / 8, t**3 / 6], [t**4 / 8, t**3 / 3, t**2 / 2], [t**3 / 6, t**2 / 2, t]])
    return _interleave(q1)


def _interleave(m: NDArray) -> NDArray[np.float64]:
    """Per-axis 3×3 [pos, vel, acc] block -> 6×6 on [x, y, vx, vy, ax, ay]."""
    return np.kron(m, np.eye(2))


def _h_terms(dx: NDArray, dy: NDArray, dh_m: float, variant: str) -> NDArray[np.float64]:
    """h per RRH, [..., per] (AOD [rad] then TOA [s]), from the train-minus-RRH offsets
    dx, dy [...] [m] (seed eq. 14, 3-D range with the known height difference)."""
    use_aod, use_toa = VARIANTS[variant]
    out = np.empty(np.shape(dx) + (int(use_aod) + int(use_toa),))
    if use_aod:
        out[..., 0] = np.arctan2(dy, dx)
    if use_toa:
        out[..., -1] = np.sqrt(dx**2 + dy**2 + dh_m**2) / SPEED_OF_LIGHT_M_S
    return out


def _jac_terms(dx: NDArray, dy: NDArray, dh_m: float, variant: str) -> NDArray[np.float64]:
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
    h = _h_terms(s[0] - rrh_xy[:, 0], s[1] - rrh_xy[:, 1], dh_m, variant)
    return h.ravel()  # [aod_0, toa_0, aod_1, toa_1, ...]


def jacobian(s: NDArray, rrh_xy: NDArray, dh_m: float, variant: str) -> NDArray[np.float64]:
    """Analytic ∂h/∂s at s: [n·m, 6] (only x, y enter)."""
    jac = _jac_terms(s[0] - rrh_xy[:, 0], s[1] - rrh_xy[:, 1], dh_m, variant)
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


@dataclass(frozen=True)
class TrackerConfig:
    """Tracker settings [ours unless noted].

    variant: ``aod``, ``toa`` or ``aod_toa`` [seed]; q: white-jerk intensity [m² s⁻⁵];
    sigma_aod_rad, sigma_toa_s: measurement noise standard deviations; gate: χ² innovation
    gate per RRH at ``gate_prob``. Distance-dependent W [ours, an option]: with
    ``distance_edges_m`` (increasing 2-D train–RRH distances [m]) the standard deviations of
    a measurement are those of its distance bin, ``sigma_aod_bins_rad`` and
    ``sigma_toa_bins_s`` (one more entry than edges), at the predicted distance.
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
        """The calibrated quantities as stored in ``calibration.json``."""
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
        """Inverse of :meth:`record` (``kw``: variant, gate, gate_prob)."""
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


def distances_m(s: NDArray, rrh_xy: NDArray) -> NDArray[np.float64]:
    """2-D distances [m] from the position in state (or position) ``s`` to ``rrh_xy`` [n, 2]."""
    return np.hypot(s[0] - rrh_xy[:, 0], s[1] - rrh_xy[:, 1])


def snapshot_ls(
    rrh_xy: NDArray, aod: NDArray, toa: NDArray, dh_m: float, cfg: TrackerConfig, x_init: NDArray, n_iter: int = 20
) -> tuple[NDArray, NDArray]:
    """Weighted Gauss–Newton position fix [x, y] from one epoch and its covariance [m²]
    (:func:`snapshot_ls_batch` for one epoch)."""
    rrh_xy = np.asarray(rrh_xy, float).reshape(-1, 2)
    p, cov = snapshot_ls_batch(
        rrh_xy[None],
        np.asarray(aod, float).reshape(1, -1),
        np.asarray(toa, float).reshape(1, -1),
        dh_m,
        cfg,
        np.asarray(x_init, float).reshape(1, 2),
        n_iter,
        with_cov=True,
    )
    return p[0], cov[0]


def snapshot_ls_batch(
    rrh_xy: NDArray,
    aod: NDArray,
    toa: NDArray,
    dh_m: float,
    cfg: TrackerConfig,
    x_init: NDArray,
    n_iter: int = 20,
    with_cov: bool = False,
) -> tuple[NDArray, NDArray | None]:
    """Weighted Gauss–Newton position fixes of independent epochs, all at once.

    ``rrh_xy`` [E, m, 2], ``aod``/``toa`` [E, m] (NaN RRH positions pad epochs with fewer
    measurements; every epoch needs at least one), ``x_init`` [E, 2]. Each epoch iterates
    p ← p + (JᵀWJ)⁻¹ JᵀW (z - h(p)) (angle residuals wrapped) until its step is under 1 µm,
    at most ``n_iter`` times, and stops early where det JᵀWJ = 0; W is the inverse of
    :meth:`TrackerConfig.noise` at the initial guess. Returns the fixes [E, 2] and, with
    ``with_cov``, the covariances pinv(JᵀWJ) at the fixes [E, 2, 2] [m²].
    """
    xy = np.asarray(rrh_xy, float)
    valid = np.isfinite(xy[..., 0])  # [E, m]
    if not valid.any(axis=1).all():
        raise ValueError("rrh_xy: every epoch needs at least one measured RRH")
    xy = np.where(valid[..., None], xy, 0.0)
    use_aod, use_toa = VARIANTS[cfg.variant]
    n_e = valid.shape[0]
    p = np.asarray(x_init, float).copy()
    # weights [E, m, per] at the initial guess (0 for padding)
    dist0 = np.hypot(p[:, :1] - xy[..., 0], p[:, 1:] - xy[..., 1])
    var = cfg.variances(dist0)
    w = np.where(valid[..., None], 1.0 / var, 0.0)
    z = np.stack(([np.asarray(aod, float)] if use_aod else []) + ([np.asarray(toa, float)] if use_toa else []), axis=-1)
    z = np.where(valid[..., None], z, 0.0)

    def lin(idx):
        """J [e, m, per, 2] and wrapped residuals [e, m, per] of the epochs ``idx`` at p."""
        ok = valid[idx]
        dx = np.where(ok, p[idx, :1] - xy[idx, :, 0], 1.0)
        dy = np.where(ok, p[idx, 1:] - xy[idx, :, 1], 1.0)
        jac = _jac_terms(dx, dy, dh_m, cfg.variant)
        h = _h_terms(dx, dy, dh_m, cfg.variant)
        r = z[idx] - h
        if use_aod:
            r[..., 0] = wrap_rad(r[..., 0])
        return jac, np.where(ok[..., None], r, 0.0)

    def normal(idx, jac, r=None):
        info = np.einsum("empi,emp,empj->eij", jac, w[idx], jac)
        return info, (None if r is None else np.einsum("empi,emp,emp->ei", jac, w[idx], r))

    active = np.ones(n_e, dtype=bool)
    for _ in range(n_iter):
        if not active.any():
            break
        idx = np.flatnonzero(active)
        jac, r = lin(idx)
        info, g = normal(idx, jac, r)
        # 2 × 2 solve in closed form; a singular JᵀWJ stops that epoch
        det = info[:, 0, 0] * info[:, 1, 1] - info[:, 0, 1] * info[:, 1, 0]
        ok = det != 0
        det = np.where(ok, det, 1.0)
        step = (
            np.stack(
                [info[:, 1, 1] * g[:, 0] - info[:, 0, 1] * g[:, 1], info[:, 0, 0] * g[:, 1] - info[:, 1, 0] * g[:, 0]],
                axis=1,
            )
            / det[:, None]
        )
        p[idx[ok]] += step[ok]
        done = ~ok | (np.linalg.norm(step, axis=1) < 1e-6)
        active[idx[done]] = False
    if not with_cov:
        return p, None
    idx = np.arange(n_e)
    jac, _ = lin(idx)
    return p, np.linalg.pinv(normal(idx, jac)[0])


def run_ekf(
    rrh_xy,
    aod,
    toa,
    dt_s: float,
    dh_m: float,
    cfg: TrackerConfig,
    s0: NDArray,
    p0: NDArray,
    n_epochs: int | None = None,
    reacquire=None,
    reacquire_after: int = 10,
) -> dict[str, NDArray]:
    """Run the EKF over epochs; epoch n has measurements from RRHs ``rrh_xy[n]`` [m_n, 2]
    (possibly none: prediction only). ``rrh_xy`` may instead be a callable
    ``select(n, x_pred) -> (rrh_xy, aod, toa)`` choosing the measurements from the
    predicted state (then ``aod``/``toa`` are ignored and ``n_epochs`` is required).
    With the gate on, ``reacquire(n) -> (position [2], covariance [2, 2]) | None`` re-seeds
    the position after ``reacquire_after`` consecutive epochs whose measurements were all
    rejected (track loss: a gate alone never lets a lost filter back) [ours].

    Returns
    -------
    dict with ``state`` [n, 6] (posterior), ``cov`` [n, 6, 6], ``nis`` [n] (NaN without
    measurements), ``n_used`` [n] (RRHs used after gating).
    """
    f = transition(dt_s)
    ekf = ExtendedKalmanFilter(dim_x=6, dim_z=1)
    ekf.x = np.asarray(s0, float).copy()
    ekf.P = np.asarray(p0, float).copy()
    ekf.F = f
    ekf.Q = process_noise(dt_s, cfg.q)
    res = residual_fn(cfg.variant)
    per = sum(VARIANTS[cfg.variant])
    select = rrh_xy if callable(rrh_xy) else None
    n = n_epochs if select is not None else len(rrh_xy)
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
        if select is not None:
            xy, aod_k, toa_k = select(k, ekf.x)
        else:
            xy, aod_k, toa_k = rrh_xy[k], aod[k], toa[k]
        xy = np.asarray(xy, float).reshape(-1, 2)
        if xy.shape[0]:
            z = cfg.pick(np.asarray(aod_k), np.asarray(toa_k))
            m_k = xy.shape[0]
            # h, ∂h/∂s and the RRH distances at the prediction, once for the gate and the
            # update (filterpy evaluates them at the same ekf.x: the kept RRHs' rows)
            dx, dy = ekf.x[0] - xy[:, 0], ekf.x[1] - xy[:, 1]
            h_all = np.zeros((m_k, per, 6))
            h_all[..., :2] = _jac_terms(dx, dy, dh_m, cfg.variant)
            hx_all = _h_terms(dx, dy, dh_m, cfg.variant)  # [m_k, per]
            var_all = cfg.variances(np.hypot(dx, dy))  # [m_k, per]
            keep = np.ones(m_k, dtype=bool)
            if cfg.gate:  # per-RRH χ² test on the predicted innovation (all RRHs at once)
                s_i = np.einsum("ipa,ab,iqb->ipq", h_all, ekf.P, h_all)  # H_i P H_iᵀ
                s_i[:, np.arange(per), np.arange(per)] += var_all
                r_i = res(z, hx_all.ravel()).reshape(m_k, per)
                d2 = np.einsum("ip,ip->i", r_i, np.linalg.solve(s_i, r_i[..., None])[..., 0])
                keep = d2 <= gate
            if keep.any():
                if not keep.all():
                    h_all, hx_all, var_all, z = h_all[keep], hx_all[keep], var_all[keep], z[np.repeat(keep, per)]
                h_k, hx_k = h_all.reshape(-1, 6), hx_all.ravel()
                ekf.update(z, lambda s, h=h_k: h, lambda s, hx=hx_k: hx, R=np.diag(var_all.ravel()), residual=res)
                nis[k] = float(ekf.y @ np.linalg.solve(ekf.S, ekf.y))
                used[k] = int(keep.sum())
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


def track_setup(
    ds, rrh_x: NDArray, rrh_y: float, dh_m: float, cfg: TrackerConfig, strength: str, n_use: int, lever_arm: bool = True
):
    """Measurement selection ``pick(k, x_pred)``, the snapshot re-acquisition fix
    ``snapshot_fix(k, x_pred)``, the first epoch with measurements k0, the initial state and
    P0 (snapshot LS position at rest; speed and acceleration σ 1 m/s and 1 m/s² [ours]) and
    the number of epochs: the set-up shared by :func:`track` and the IMM.

    Separate head/tail panels (``ds["train_panel_x"]`` nonzero): each measurement is taken
    at the panel facing its RRH at the predicted position (:func:`railradio.nr.antenna.facing_panel`),
    whose along-track lever arm ℓ enters h(x) as an RRH shifted by -ℓ (on the straight
    track, x + ℓ - x_k = x - (x_k - ℓ); the Jacobian is unchanged). ``lever_arm=False``
    ignores it: the seed's point model [ours]."""
    from railradio.nr.antenna import facing_panel

    panel_x = tuple(float(v) for v in ds["train_panel_x"].values) if lever_arm and "train_panel_x" in ds else (0.0, 0.0)
    rrh = ds["rrh"].values
    aod = ds["aod_hat"].values
    toa = ds["toa_hat"].values
    ok = np.isfinite(aod) & np.isfinite(toa)
    stren = np.nan_to_num(ds[strength].values, nan=-np.inf)

    def pick(k: int, x_pred: float):
        cols = select_measurements(rrh[k], ok[k], stren[k], rrh_x, x_pred, rrh.shape[1], n_use)
        x_k = rrh_x[rrh[k, cols]]
        if panel_x != (0.0, 0.0):  # lever arm of the panel facing each RRH
            x_k = x_k - np.asarray(panel_x)[facing_panel(x_pred, x_k, rrh_y, panel_x)]
        xy = np.stack([x_k, np.full(cols.size, rrh_y)], axis=1) if cols.size else np.zeros((0, 2))
        return xy, aod[k, cols], toa[k, cols]

    def snapshot_fix(k: int, x_pred: float):
        """LS fix from the measurements picked around ``x_pred``, started at the strongest
        one's own closed form x_k + ρ (cos θ, sin θ) (ρ the horizontal range); None when
        nothing is measured or the LS runs away (farther from that RRH than its measured
        range plus 1 km)."""
        xy, a_k, t_k = pick(k, x_pred)
        if xy.shape[0] == 0:
            return None
        rho = np.sqrt(max((SPEED_OF_LIGHT_M_S * t_k[0]) ** 2 - dh_m**2, 1.0))
        guess = np.array([xy[0, 0] + rho * np.cos(a_k[0]), xy[0, 1] + rho * np.sin(a_k[0])])
        fix, cov = snapshot_ls(xy, a_k, t_k, dh_m, cfg, guess)
        if not (np.all(np.isfinite(fix)) and np.all(np.isfinite(cov)) and np.hypot(*(fix - xy[0])) <= rho + 1000.0):
            return None
        return fix, cov

    # the start: the first epoch whose strongest measured cell gives a fix (no truth)
    k0, start = 0, None
    for k in np.flatnonzero(ok.any(axis=1)):
        start = snapshot_fix(int(k), anchor_x(rrh[k], ok[k], stren[k], rrh_x))
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

    return pick, snapshot_fix, k0, s0, p0, rrh.shape[0]


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
    """
    pick, snapshot_fix, k0, s0, p0, n = track_setup(ds, rrh_x, rrh_y, dh_m, cfg, strength, n_use, lever_arm)
    rrh = ds["rrh"].values

    state_now = {"x": s0[0]}

    def select(k: int, s):
        state_now["x"] = float(s[0])
        return pick(k + k0, float(s[0]))

    out = run_ekf(
        select,
        None,
        None,
        dt_s,
        dh_m,
        cfg,
        s0,
        p0,
        n_epochs=n - k0,
        reacquire=lambda k: snapshot_fix(k + k0, state_now["x"]) if cfg.gate else None,
    )
    state = np.full((n, 6), np.nan)
    state[k0:] = out["state"]
    cov = np.full((n, 6, 6), np.nan)
    cov[k0:] = out["cov"]
    nis = np.full(n, np.nan)
    nis[k0:] = out["nis"]
    used = np.zeros(n, dtype=np.int64)
    used[k0:] = out["n_used"]
    # snapshot LS baseline: no tracking; each epoch's measurements are those around its
    # strongest measured cell, and each fix starts from that cell's own AOD/TOA closed
    # form x_k + ρ cos θ (ρ the horizontal range)
    snap = np.full((n, 2), np.nan)
    if snapshot:
        ok = np.isfinite(ds["aod_hat"].values) & np.isfinite(ds["toa_hat"].values)
        stren = np.nan_to_num(ds[strength].values, nan=-np.inf)
        xy_all = np.full((n, n_use, 2), np.nan)
        a_all = np.full((n, n_use), np.nan)
        t_all = np.full((n, n_use), np.nan)
        for k in range(n):
            if not ok[k].any():
                continue
            xy, a_k, t_k = pick(k, anchor_x(rrh[k], ok[k], stren[k], rrh_x))
            j = xy.shape[0]
            xy_all[k, :j], a_all[k, :j], t_all[k, :j] = xy, a_k, t_k
        has = np.isfinite(xy_all[:, 0, 0])
        if has.any():
            xy0, a0, t0 = xy_all[has, 0], a_all[has, 0], t_all[has, 0]
            rho = np.sqrt(np.maximum((SPEED_OF_LIGHT_M_S * t0) ** 2 - dh_m**2, 1.0))
            guess = np.stack([xy0[:, 0] + rho * np.cos(a0), xy0[:, 1] + rho * np.sin(a0)], axis=1)
            snap[has], _ = snapshot_ls_batch(xy_all[has], a_all[has], t_all[has], dh_m, cfg, guess)
    reac = np.zeros(n, dtype=bool)
    reac[k0:] = out["reacquired"]
    return {"state": state, "cov": cov, "nis": nis, "n_used": used, "snapshot": snap, "k0": k0, "reacquired": reac}


def nees_position(state: NDArray, cov: NDArray, x_true: NDArray) -> NDArray[np.float64]:
    """Normalized estimation error squared of the 2-D position, eᵀ P_pos⁻¹ e per epoch
    (e = estimate − truth, the train at y = 0); χ²₂-distributed for a consistent filter
    (mean 2). NaN before the track starts. Scoring only: it uses the truth."""
    e = np.stack([state[:, 0] - np.asarray(x_true, float), state[:, 1]], axis=1)
    p = cov[:, :2, :2]
    det = p[:, 0, 0] * p[:, 1, 1] - p[:, 0, 1] * p[:, 1, 0]
    with np.errstate(invalid="ignore", divide="ignore"):
        q = (p[:, 1, 1] * e[:, 0] ** 2 - 2 * p[:, 0, 1] * e[:, 0] * e[:, 1] + p[:, 0, 0] * e[:, 1] ** 2) / det
    return np.where(np.isfinite(q), q, np.nan)


def selected(ds, strength: str = "peak", n_use: int = 3) -> tuple[NDArray, NDArray]:
    """The candidates a receiver measures per epoch: ``(order, ok)``, [epoch, n_use] column
    indices of the ``n_use`` strongest by ``strength`` among those with an AOD and a TOA,
    and whether each holds a measurement."""
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
    returns (flat only) the true 3-D distances [m] of those measurements."""
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
    outliers (another RRH's peak, a false detection) then do not set W [ours]."""
    from scipy.stats import norm

    e = np.asarray(e, float)
    e = e[np.isfinite(e)]
    if e.size == 0:
        return float("nan"), 0.0
    k = float(np.sqrt(chi2.ppf(gate_prob, 1)))
    shrink = 1.0 - 2 * k * norm.pdf(k) / (2 * norm.cdf(k) - 1)
    c = float(np.median(e))
    sig = 1.4826 * float(np.median(np.abs(e - c)))
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
    errors takes the overall values), returned as :class:`TrackerConfig` keyword arguments."""

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
    variant: str,
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
) -> TrackerConfig:
    """Measurement and process noise from a calibration run (never the evaluation run).

    W: σ_AOD, σ_TOA of the inliers of the selected measurements' errors, those a χ² gate
    at ``gate_prob`` keeps (:func:`inlier_sigma`), the TOA one floored at the
    integer-sample quantization 1/(√12 F_s); with ``distance_edges_m``, also per bin of the
    true 2-D distance (a bin with fewer than ``min_per_bin`` measurements takes the overall
    values). q: the value whose position NEES on the calibration run (whose truth is
    legitimately known) is consistent, |log(median NEES / median χ²₂)| smallest, over
    ``q_grid``; when an edge of the grid wins, the grid is extended by decades beyond it up
    to :data:`Q_SEARCH_LIMITS`. ``search`` (a dict) receives the q values tried, their
    costs, whether the winner sits on the searched range's edge and whether the cost is
    monotone toward it (the search reached the limit with the cost falling at every decade
    from the grid's edge on: no q is identified, the finding to report instead of a q).
    """
    e_aod, e_rng, d3 = measurement_errors(ds, strength, with_distance=True)
    dist = np.sqrt(np.maximum(d3**2 - dh_m**2, 0.0))  # 2-D, as the tracker predicts it
    s_aod, s_toa, bins = robust_sigmas(e_aod, e_rng, dist, distance_edges_m, min_per_bin, fs_hz, gate_prob)
    qs = sorted(float(q) for q in q_grid)
    if not qs:
        raise ValueError("q_grid must not be empty")
    cost: dict[float, float] = {}

    def cfg_of(q):
        return TrackerConfig(
            variant=variant,
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
    tried = sorted(cost)
    c = np.array([cost[q] for q in tried])
    if search is not None:
        # monotone toward the edge: the search widened to the limit and the cost fell at
        # every decade from the grid's edge on (no minimum inside the limits)
        if best == tried[-1] and best * 10 > hi:
            toward = c[np.asarray(tried) >= qs[-1]]
        elif best == tried[0] and best / 10 < lo:
            toward = c[np.asarray(tried) <= qs[0]][::-1]
        else:
            toward = np.array([])
        search.update(
            q=tried,
            cost=[float(v) if np.isfinite(v) else None for v in c],
            at_edge=bool(best in (tried[0], tried[-1])),
            monotone=bool(toward.size > 1 and np.all(np.isfinite(toward)) and np.all(np.diff(toward) < 0)),
        )
    return cfg_of(best)


KEY_SYNC = 4
"""Sub-key of the clock offsets below a realization's spawn key (the simulation uses 1–3:
:data:`railradio.nr.simulate.KEY_EPOCH` and its siblings)."""


def clock_offsets_s(seed: int, key: tuple[int, ...], rrh: NDArray, rrh_sigma_s: float) -> NDArray[np.float64]:
    """Timing offset [s] of each RRH in ``rrh`` against the network's time reference: one
    N(0, σ²) draw per realization and RRH, keyed (realization key, KEY_SYNC, RRH id), so
    an RRH keeps its offset along the whole run and whatever the sharding [ours]."""
    if not rrh_sigma_s >= 0:
        raise ValueError(f"rrh_sigma_s must be >= 0 [s], got {rrh_sigma_s!r}")
    from railradio.rng import make_rng

    rrh = np.asarray(rrh, dtype=np.int64)
    if rrh_sigma_s == 0:
        return np.zeros(rrh.shape)
    ids, inv = np.unique(rrh, return_inverse=True)
    off = np.array([make_rng(seed, tuple(key) + (KEY_SYNC, int(r))).standard_normal() for r in ids])
    return (rrh_sigma_s * off)[inv].reshape(rrh.shape)


def apply_clock_errors(ds, seed: int, key: tuple[int, ...], rrh_sigma_s: float = 0.0, train_bias_s: float = 0.0):
    """The estimates ``ds`` as measured with imperfect clocks: every TOA of RRH k is late by
    its offset δ_k (:func:`clock_offsets_s`) plus the train clock's bias b, which the tracker
    does not know (its calibration run has its own offsets, so the calibrated σ_TOA holds
    their spread).

    A timing offset delays the RRH's whole burst; the correlator's TOA then moves by the
    same amount, so adding δ_k + b to the measured TOA equals re-synthesizing with the
    shifted delay up to the integer-sample quantization: round(τ + δ) - τ and round(τ) - τ + δ
    differ per epoch by under one sample but have the same distribution when the
    fractional delay is uniform; the offsets (nanoseconds) are far below the SS-block
    spacing, so detection and AOD do not change [ours]. Zero offsets return ``ds`` itself.
    """
    if not np.isfinite(train_bias_s):
        raise ValueError(f"train_bias_s must be finite [s], got {train_bias_s!r}")
    if rrh_sigma_s == 0 and train_bias_s == 0:
        return ds
    off = clock_offsets_s(seed, key, ds["rrh"].values, rrh_sigma_s) + train_bias_s  # [epoch, cand]
    out = ds.copy()
    out["toa_hat"] = ds["toa_hat"] + ds["rrh"].copy(data=off)
    out["toa_hat"].attrs = dict(ds["toa_hat"].attrs)
    return out
