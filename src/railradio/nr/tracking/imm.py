"""Tracking that does not lag (docs/model/nr.md §6): an interacting-multiple-model
(IMM) filter of white-jerk constant-acceleration EKFs, run with the same measurement
selection, χ² gate and re-acquisition as :func:`railradio.nr.tracking.track.track`.

IMM cycle (Blom & Bar-Shalom 1988; Bar-Shalom, Li & Kirubarajan 2001, §11.6.6, "BLK"):

1. mixing: c̄_j = Σ_i p_ij μ_i, μ_i|j = p_ij μ_i / c̄_j (BLK eq. 11.6.6-8, -9);
   x0_j = Σ_i μ_i|j x_i, P0_j = Σ_i μ_i|j [P_i + (x_i − x0_j)(x_i − x0_j)ᵀ] (-10, -11);
2. each model's EKF prediction with its own white-jerk intensity q_j and update with the
   common validated measurements; likelihood Λ_j = N(ν_j; 0, S_j) (-12);
3. mode probabilities μ_j = Λ_j c̄_j / Σ_l Λ_l c̄_l (-15);
4. combination x = Σ_j μ_j x_j, P = Σ_j μ_j [P_j + (x_j − x)(x_j − x)ᵀ] (-16, -17).

Markov transition matrix from the mean sojourn time τ_j of each mode: a geometric
sojourn of mean τ_j epochs·dt has p_jj = 1 − dt/τ_j (BLK §11.6.3); the rest of the row is
shared equally by the other modes [ours]. The manoeuvre model's intensity follows the
rule that the acceleration changes over one interval T by about √(qT) (BLK §6.2.3):
q = Δa²/T for a jump Δa [m/s²] [ours: Δa from config].

Selection and gate [ours]: the measured RRHs are chosen from the mode-weighted predicted
position; a measurement passes the χ² gate if it passes the gate of at least one model
(the union of the models' validation regions), so that the manoeuvre model can still see
the measurements the quiet model's gate would reject. With one model every step reduces to
:func:`railradio.nr.tracking.ekf.run_ekf` (a test checks equality).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2

from railradio.nr.tracking.dynamics import process_noise, transition
from railradio.nr.tracking.ekf import Reacquire, Select, TrackerConfig, run_ekf
from railradio.nr.tracking.measurement import MEASUREMENT_SETS, jacobian, residual_fn
from railradio.nr.tracking.track import track_setup


def markov_matrix(sojourn_s, dt_s: float) -> NDArray[np.float64]:
    """Mode transition matrix Π[i, j] = P(mode j at k+1 | mode i at k) from the mean
    sojourn times ``sojourn_s`` [s] of the modes: p_ii = 1 − dt/τ_i (BLK §11.6.3), the
    remainder split equally among the other modes. One mode: [[1]].

    Parameters
    ----------
    sojourn_s : float or sequence of float
        Mean sojourn time τ_j of each of the m modes [s], [m].
    dt_s : float
        Epoch interval [s]; > 0.

    Returns
    -------
    numpy.ndarray
        [m, m] row-stochastic transition matrix Π [1].

    Raises
    ------
    ValueError
        When ``dt_s`` is not > 0, ``sojourn_s`` is empty or not 1-D, or (with more than one mode)
        a sojourn time is shorter than ``dt_s``.
    """
    tau = np.atleast_1d(np.asarray(sojourn_s, dtype=float))
    if not dt_s > 0:
        raise ValueError(f"dt_s must be > 0 [s], got {dt_s!r}")
    if tau.ndim != 1 or tau.size == 0:
        raise ValueError("sojourn_s must be a non-empty list of times [s]")
    m = tau.size
    if m == 1:
        return np.ones((1, 1))
    if not np.all(tau >= dt_s):
        raise ValueError(f"sojourn_s must all be >= dt_s = {dt_s} s, got {tau.tolist()}")
    stay = 1.0 - dt_s / tau
    pi = np.repeat(((1.0 - stay) / (m - 1))[:, None], m, axis=1)
    np.fill_diagonal(pi, stay)
    return pi


def stationary(pi: NDArray) -> NDArray[np.float64]:
    """Stationary distribution μ = μ Π of a Markov matrix (the initial mode probabilities).

    Parameters
    ----------
    pi : numpy.ndarray
        [m, m] Markov transition matrix Π [1] (:func:`markov_matrix`).

    Returns
    -------
    numpy.ndarray
        [m] mode probabilities μ [1], summing to 1 (the left eigenvector of Π whose
        eigenvalue is nearest 1).
    """
    w, v = np.linalg.eig(np.asarray(pi, float).T)
    mu = np.real(v[:, np.argmin(np.abs(w - 1.0))])
    return mu / mu.sum()


def q_for_jump(delta_a_m_s2: float, dt_s: float) -> float:
    """White-jerk intensity [m² s⁻⁵] whose acceleration change over one interval,
    √(q·T), equals the jump Δa [m/s²] (BLK §6.2.3): q = Δa²/T.

    Parameters
    ----------
    delta_a_m_s2 : float
        Acceleration jump Δa [m/s²]; > 0.
    dt_s : float
        Epoch interval T [s]; > 0.

    Returns
    -------
    float
        White-jerk intensity q [m² s⁻⁵].

    Raises
    ------
    ValueError
        When ``delta_a_m_s2`` or ``dt_s`` is not > 0.
    """
    if not delta_a_m_s2 > 0:
        raise ValueError(f"delta_a_m_s2 must be > 0 [m/s²], got {delta_a_m_s2!r}")
    if not dt_s > 0:
        raise ValueError(f"dt_s must be > 0 [s], got {dt_s!r}")
    return float(delta_a_m_s2) ** 2 / float(dt_s)


@dataclass(frozen=True)
class ImmConfig:
    """Model set of the IMM: white-jerk intensities ``q`` [m² s⁻⁵] and mean sojourn times
    ``sojourn_s`` [s], one per model (the first is the quiet model); ``mu0``: initial mode
    probabilities (None: the stationary distribution of the Markov chain).

    Attributes
    ----------
    q : tuple of float
        White-jerk intensity of each model [m² s⁻⁵], [m]; > 0.
    sojourn_s : tuple of float
        Mean sojourn time of each mode [s], [m]; > 0.
    mu0 : tuple of float or None
        Initial mode probabilities [1], [m], summing to 1; None: stationary.

    Raises
    ------
    ValueError
        When ``q`` is empty or not > 0, ``sojourn_s`` has not one positive entry per model, or
        ``mu0`` is not m probabilities summing to 1.
    """

    q: tuple[float, ...]
    sojourn_s: tuple[float, ...]
    mu0: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        q = np.atleast_1d(np.asarray(self.q, float))
        if q.size == 0 or not np.all(q > 0):
            raise ValueError(f"q must be a non-empty list of values > 0 [m² s⁻⁵], got {self.q!r}")
        if len(np.atleast_1d(self.sojourn_s)) != q.size:
            raise ValueError(f"sojourn_s must have one entry per model ({q.size}), got {self.sojourn_s!r}")
        if not np.all(np.asarray(self.sojourn_s, float) > 0):
            raise ValueError(f"sojourn_s must be > 0 [s], got {self.sojourn_s!r}")
        if self.mu0 is not None:
            mu0 = np.asarray(self.mu0, float)
            if mu0.shape != q.shape or np.any(mu0 < 0) or not np.isclose(mu0.sum(), 1.0):
                raise ValueError(f"mu0 must be {q.size} probabilities summing to 1, got {self.mu0!r}")

    @property
    def n_models(self) -> int:
        """Number of models m."""
        return len(np.atleast_1d(self.q))

    def initial(self, dt_s: float) -> tuple[NDArray, NDArray]:
        """(Π, μ0) for interval ``dt_s``.

        Parameters
        ----------
        dt_s : float
            Epoch interval [s]; > 0.

        Returns
        -------
        tuple of numpy.ndarray
            ``(pi, mu0)``: Markov matrix Π [m, m] (:func:`markov_matrix`) and initial mode
            probabilities [m] (``mu0``, or :func:`stationary` of Π) [1].

        Raises
        ------
        ValueError
            From :func:`markov_matrix` (``dt_s`` not > 0 or a sojourn time shorter than it).
        """
        pi = markov_matrix(self.sojourn_s, dt_s)
        mu0 = stationary(pi) if self.mu0 is None else np.asarray(self.mu0, float)
        return pi, mu0


def _gauss_logpdf(nu: NDArray, s: NDArray) -> tuple[float, float]:
    """(log N(ν; 0, S), νᵀS⁻¹ν), with S scaled to unit diagonal first: the AOD [rad] and
    TOA [s] entries differ by ~10 orders of magnitude."""
    d = 1.0 / np.sqrt(np.diag(s))
    sc = s * np.outer(d, d)
    nus = nu * d
    chol = np.linalg.cholesky(sc)
    w = np.linalg.solve(chol, nus)
    maha = float(w @ w)
    logdet = 2.0 * np.sum(np.log(np.diag(chol))) - 2.0 * np.sum(np.log(d))
    return -0.5 * (maha + logdet + nu.size * np.log(2 * np.pi)), maha


def _moments(mu: NDArray, xs: NDArray, ps: NDArray) -> tuple[NDArray, NDArray]:
    """Mixture mean and covariance (BLK eq. 11.6.6-16, -17) of models ``xs`` [m, 6], ``ps``."""
    x = mu @ xs
    d = xs - x
    return x, np.einsum("j,jab->ab", mu, ps) + np.einsum("j,ja,jb->ab", mu, d, d)


def run_imm(
    select: Select,
    dt_s: float,
    dh_m: float,
    cfg: TrackerConfig,
    imm: ImmConfig,
    s0: NDArray,
    p0: NDArray,
    n_epochs: int,
    reacquire: Reacquire | None = None,
    reacquire_after: int = 10,
) -> dict[str, NDArray]:
    """Run the IMM over ``n_epochs`` epochs; ``select(n, x_pred) -> (rrh_xy, aod, toa)`` and
    ``reacquire`` as in :func:`railradio.nr.tracking.ekf.run_ekf` (measurement noise, measurement set and
    gate from ``cfg``; its ``q`` is not used: each model has its own).

    Returns ``state`` [n, 6] and ``cov`` [n, 6, 6] (combined posterior), ``mu`` [n, m] (mode
    probabilities), ``n_used`` [n] (RRHs used after gating), ``reacquired`` [n].

    Parameters
    ----------
    select : Select
        ``select(n, x_pred) -> (rrh_xy [m_n, 2] [m], aod [m_n] [rad], toa [m_n] [s])``, the
        measurements of epoch n chosen from the mode-weighted predicted state [6].
    dt_s : float
        Epoch interval [s].
    dh_m : float
        Height difference between the RRHs and the train antenna [m].
    cfg : TrackerConfig
        Measurement set, measurement noise W and gate (its ``q`` is not used).
    imm : ImmConfig
        The model set.
    s0, p0 : numpy.ndarray
        Initial state [6] (x, y [m], v_x, v_y [m/s], a_x, a_y [m/s²]) and covariance [6, 6]
        (SI units squared), common to every model.
    n_epochs : int
        Epochs to run; >= 0.
    reacquire : Reacquire or None
        ``reacquire(n) -> (position [2] [m], covariance [2, 2] [m²]) | None``; None: never.
    reacquire_after : int
        Consecutive epochs with all measurements rejected before ``reacquire`` is called; >= 1.

    Returns
    -------
    dict of str to numpy.ndarray
        ``state`` [n, 6], ``cov`` [n, 6, 6] (units as ``s0``, ``p0``), ``mu`` [n, m] [1],
        ``n_used`` [n] (int), ``reacquired`` [n] (bool).

    Raises
    ------
    ValueError
        When ``n_epochs`` < 0, ``reacquire_after`` < 1, ``cfg.track_bound`` is set (the IMM's
        models are 2-D), or from :meth:`ImmConfig.initial`.
    """
    if cfg.track_bound:
        raise ValueError("cfg.track_bound is not supported by the IMM (its models estimate y): use run_ekf")
    if n_epochs < 0:
        raise ValueError(f"n_epochs must be >= 0, got {n_epochs!r}")
    if reacquire_after < 1:
        raise ValueError(f"reacquire_after must be >= 1, got {reacquire_after!r}")
    m = imm.n_models
    f = transition(dt_s)
    qs = [process_noise(dt_s, float(q)) for q in np.atleast_1d(imm.q)]
    pi, mu = imm.initial(dt_s)
    xs = np.repeat(np.asarray(s0, float)[None], m, axis=0)
    ps = np.repeat(np.asarray(p0, float)[None], m, axis=0)
    res = residual_fn(cfg.measurements)
    per = sum(MEASUREMENT_SETS[cfg.measurements])
    gate = chi2.ppf(cfg.gate_prob, per) if cfg.gate else np.inf
    out = {
        "state": np.zeros((n_epochs, 6)),
        "cov": np.zeros((n_epochs, 6, 6)),
        "mu": np.zeros((n_epochs, m)),
        "n_used": np.zeros(n_epochs, dtype=np.int64),
        "reacquired": np.zeros(n_epochs, dtype=bool),
    }
    misses = 0
    for k in range(n_epochs):
        cbar = mu.copy()
        if k > 0:  # 1. mixing, 2. per-model prediction
            cbar, xs, ps = _mix_predict(mu, pi, xs, ps, f, qs)
        x_pred = cbar @ xs
        xy, aod_k, toa_k = select(k, x_pred)
        xy = np.asarray(xy, float).reshape(-1, 2)
        if xy.shape[0]:
            z = cfg.pick(np.asarray(aod_k), np.asarray(toa_k))
            keep = np.ones(xy.shape[0], dtype=bool)
            if cfg.gate:  # per-RRH χ² test, passed if any model's gate passes it
                keep = _union_gate(xs, ps, xy, z, dh_m, cfg, res, gate)
            if keep.any():
                sel = xy[keep]
                zs = z[np.repeat(keep, per)]
                r = cfg.noise_at(x_pred, sel, dh_m)
                loglik = _update_models(xs, ps, sel, zs, r, dh_m, cfg, res)
                # 3. mode probabilities (log-sum-exp)
                lw = loglik + np.log(np.maximum(cbar, 1e-300))
                w = np.exp(lw - lw.max())
                mu = w / w.sum()
                out["n_used"][k] = int(keep.sum())
                misses = 0
            else:
                mu = cbar
                misses += 1
                if reacquire is not None and misses >= reacquire_after:
                    fix = reacquire(k)
                    if fix is not None:
                        _reseed(xs, ps, fix)
                        out["reacquired"][k] = True
                        misses = 0
        else:
            mu = cbar
        out["state"][k], out["cov"][k] = _moments(mu, xs, ps)
        out["mu"][k] = mu
    return out


def _reseed(xs: NDArray, ps: NDArray, fix: tuple[NDArray, NDArray]) -> None:
    """Re-initialise, in place, every model's position from ``fix`` (position [2], covariance
    [2, 2]), its cross-covariances with the other state components zeroed."""
    xs[:, :2] = fix[0]
    ps[:, :2, :] = 0.0
    ps[:, :, :2] = 0.0
    ps[:, :2, :2] = fix[1]


def _mix_predict(
    mu: NDArray, pi: NDArray, xs: NDArray, ps: NDArray, f: NDArray, qs: list[NDArray]
) -> tuple[NDArray, NDArray, NDArray]:
    """1. mixing (BLK eq. 11.6.6-8 to -11) of the models' states ``xs`` [m, 6] and
    covariances ``ps`` [m, 6, 6] with mode probabilities ``mu`` and Markov matrix ``pi``,
    2. each model's prediction with transition ``f`` and its process noise ``qs[j]``:
    returns (c̄ [m], predicted states, predicted covariances)."""
    cbar = mu @ pi
    mix = pi * mu[:, None] / np.where(cbar > 0, cbar, 1.0)[None, :]  # μ_i|j [i, j]
    x0 = mix.T @ xs
    p0m = np.empty_like(ps)
    for j in range(xs.shape[0]):
        d = xs - x0[j]
        p0m[j] = np.einsum("i,iab->ab", mix[:, j], ps) + np.einsum("i,ia,ib->ab", mix[:, j], d, d)
    xs = x0 @ f.T
    ps = np.einsum("ab,jbc,dc->jad", f, p0m, f) + np.stack(qs)
    return cbar, xs, ps


def _union_gate(
    xs: NDArray, ps: NDArray, xy: NDArray, z: NDArray, dh_m: float, cfg: TrackerConfig, res, gate: float
) -> NDArray[np.bool_]:
    """Per-RRH χ² test of the measurements ``z`` of the RRHs ``xy`` [n, 2] at threshold
    ``gate``, passed if the gate of any model (states ``xs``, covariances ``ps``) passes it."""
    per = sum(MEASUREMENT_SETS[cfg.measurements])
    keep = np.ones(xy.shape[0], dtype=bool)
    for i in range(xy.shape[0]):
        ok = False
        for j in range(xs.shape[0]):
            hi = jacobian(xs[j], xy[i : i + 1], dh_m, cfg.measurements)
            si = hi @ ps[j] @ hi.T + cfg.noise_at(xs[j], xy[i : i + 1], dh_m)
            ri = res(z[i * per : (i + 1) * per], cfg.hx(xs[j], xy[i : i + 1], dh_m))
            ok = ok or float(ri @ np.linalg.solve(si, ri)) <= gate
        keep[i] = ok
    return keep


def _update_models(
    xs: NDArray, ps: NDArray, sel: NDArray, zs: NDArray, r: NDArray, dh_m: float, cfg: TrackerConfig, res
) -> NDArray[np.float64]:
    """EKF update, in place, of every model's state ``xs[j]`` and covariance ``ps[j]`` with
    the measurements ``zs`` of the RRHs ``sel`` and their noise ``r``; returns the models'
    log-likelihoods log Λ_j (BLK eq. 11.6.6-12)."""
    eye = np.eye(6)
    loglik = np.empty(xs.shape[0])
    for j in range(xs.shape[0]):  # EKF update of model j (Joseph form, as filterpy's)
        h = jacobian(xs[j], sel, dh_m, cfg.measurements)
        pht = ps[j] @ h.T
        s = h @ pht + r
        gain = pht @ np.linalg.inv(s)
        nu = res(zs, cfg.hx(xs[j], sel, dh_m))
        loglik[j], _ = _gauss_logpdf(nu, s)
        xs[j] = xs[j] + gain @ nu
        ikh = eye - gain @ h
        ps[j] = ikh @ ps[j] @ ikh.T + gain @ r @ gain.T
    return loglik


def track_filters(
    ds,
    rrh_x: NDArray,
    rrh_y: float,
    dh_m: float,
    dt_s: float,
    cfg: TrackerConfig,
    imm: ImmConfig | None,
    strength: str = "peak",
    n_use: int = 3,
) -> dict[str, dict[str, NDArray]]:
    """Track one realization with the EKF of :func:`railradio.nr.tracking.track.track` (q =
    ``cfg.q``) and, if ``imm`` is given, the IMM, on the same selection, gate and
    re-acquisition rules. Returns ``{"ekf": ..., "imm": ...}``, each with ``state`` [n, 6],
    ``cov`` [n, 6, 6] (NaN before the first measured epoch ``k0``), ``reacquired`` [n]
    and, for the IMM, ``mu`` [n, models]; plus ``k0``.

    Parameters
    ----------
    ds : xarray.Dataset
        One receiver's estimates (:func:`railradio.nr.engine.epochs.simulate_epochs` selected at one
        ``receiver``): ``rrh``, ``aod_hat`` [rad], ``toa_hat`` [s] and the ``strength`` variable, dims
        (``epoch``, ``cand``); ``train_panel_x`` [m] for the panels' lever arm.
    rrh_x : numpy.ndarray
        [n_rrh] along-track positions of the RRHs, increasing [m].
    rrh_y : float
        Lateral offset of the RRHs from the track [m].
    dh_m : float
        Height difference between the RRHs and the train antenna [m].
    dt_s : float
        Epoch interval [s].
    cfg : TrackerConfig
        The EKF's settings (and the IMM's W, measurement set and gate).
    imm : ImmConfig or None
        The IMM's model set; None: EKF only.
    strength : str
        Variable ranking the candidates: ``"peak"``, ``"ss_rsrp"`` or ``"best_score"``.
    n_use : int
        Measured RRHs used per epoch.

    Returns
    -------
    dict
        ``"ekf"`` (and ``"imm"``): dicts of ``state`` [n, 6] (x, y [m], v [m/s], a [m/s²]),
        ``cov`` [n, 6, 6], ``reacquired`` [n] (bool) and ``mu`` [n, models] [1] (IMM);
        ``"k0"``: int.

    Raises
    ------
    ValueError
        From :meth:`ImmConfig.initial` (``dt_s`` not > 0 or a sojourn time shorter than it).
    """
    setup = track_setup(ds, rrh_x, rrh_y, dh_m, cfg, strength, n_use)
    k0, n, s0, p0 = setup.k0, setup.n_epochs, setup.s0, setup.p0
    out: dict = {"k0": k0}
    runs = {"ekf": None} | ({"imm": imm} if imm is not None else {})
    for name, model in runs.items():
        follow = setup.follower()
        if model is None:
            r = run_ekf(follow.select, dt_s, dh_m, cfg, s0, p0, n - k0, reacquire=follow.reacquire)
        else:
            r = run_imm(follow.select, dt_s, dh_m, cfg, model, s0, p0, n_epochs=n - k0, reacquire=follow.reacquire)
        full = {}
        for key in ("state", "cov", "mu", "reacquired"):
            if key in r:
                v = r[key]
                pad = np.zeros((n,) + v.shape[1:], v.dtype) if v.dtype == bool else np.full((n,) + v.shape[1:], np.nan)
                pad[k0:] = v
                full[key] = pad
        out[name] = full
    return out


def position_nees(state: NDArray, cov: NDArray, x_true: NDArray, y_true: NDArray | float = 0.0) -> NDArray:
    """2-D position NEES eᵀ P_xy⁻¹ e per epoch (χ²₂ with mean 2 for a consistent filter).

    Parameters
    ----------
    state : numpy.ndarray
        [n, 6] states (x, y [m] first).
    cov : numpy.ndarray
        [n, 6, 6] their covariances (position block [m²]).
    x_true : numpy.ndarray
        [n] true along-track positions [m].
    y_true : numpy.ndarray or float
        True lateral positions [m], [n] or scalar (0: on the track).

    Returns
    -------
    numpy.ndarray
        [n] position NEES [1]; NaN where the error or the position covariance is not finite.
    """
    e = np.stack([state[:, 0] - x_true, state[:, 1] - y_true], axis=1)
    pxy = cov[:, :2, :2]
    good = np.all(np.isfinite(e), axis=1) & np.all(np.isfinite(pxy), axis=(1, 2))
    out = np.full(state.shape[0], np.nan)
    out[good] = np.einsum("ka,ka->k", e[good], np.linalg.solve(pxy[good], e[good][..., None])[..., 0])
    return out
