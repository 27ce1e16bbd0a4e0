"""Tracking of the train from its per-RRH AOD/TOA measurements (docs/model/nr.md §6).

One realization's track: the set-up shared with the IMM (:func:`track_setup`: the measured
candidates of :mod:`railradio.nr.tracking.candidates`, the start at the first snapshot fix, the
initial state and covariance) and :func:`track`, which runs the EKF of
:mod:`railradio.nr.tracking.ekf` from that start, picking its measurements around the predicted
position and, with the gate on, re-acquiring a lost track from a snapshot fix.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from railradio.nr.tracking.candidates import MeasuredCandidates, anchor_x
from railradio.nr.tracking.ekf import TrackerConfig, run_ekf


@dataclass(frozen=True, eq=False)
class TrackSetup:
    """What :func:`track_setup` gives: the start of one realization's filter runs.

    Attributes
    ----------
    meas : MeasuredCandidates
        The realization's candidates as the tracker sees them.
    k0 : int
        The first epoch whose strongest measured cell gives a snapshot fix (0 when none
        does); the filter runs from it on.
    s0 : numpy.ndarray
        [6] initial state (x, y [m], v_x, v_y [m/s], a_x, a_y [m/s²]).
    p0 : numpy.ndarray
        [6, 6] its covariance (SI units squared).
    """

    meas: MeasuredCandidates
    k0: int
    s0: NDArray[np.float64]
    p0: NDArray[np.float64]

    @property
    def n_epochs(self) -> int:
        """Number of epochs of the realization, ``k0`` and the epochs before it included.

        Returns
        -------
        int
            :attr:`MeasuredCandidates.n_epochs` of ``meas``.
        """
        return self.meas.n_epochs

    def follower(self) -> _Follower:
        """A fresh ``select``/``reacquire`` pair for one filter run from ``k0`` on.

        Returns
        -------
        _Follower
            Its :meth:`_Follower.select` and :meth:`_Follower.reacquire` count epochs from
            ``k0`` (the filter's epoch 0 is the realization's epoch ``k0``).
        """
        return _Follower(self)


class _Follower:
    """``select`` and ``reacquire`` of one filter run from epoch k0 on
    (:func:`railradio.nr.tracking.ekf.run_ekf`, the IMM): the measurements picked around the
    predicted along-track position; with the gate on, the snapshot fix around the last such
    position. It remembers that position between the calls, so each run needs its own.

    Parameters
    ----------
    setup : TrackSetup
        The measured candidates, ``k0`` and the initial state (whose x is the remembered
        position until the first ``select``).
    """

    def __init__(self, setup: TrackSetup) -> None:
        self._setup = setup
        self._x = setup.s0[0]

    def select(self, k: int, s: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        """The measurements of filter epoch ``k`` (:data:`railradio.nr.tracking.ekf.Select`), picked
        around the predicted along-track position, which it remembers for :meth:`reacquire`.

        Parameters
        ----------
        k : int
            Filter epoch (the realization's epoch ``k + k0``).
        s : numpy.ndarray
            [6] predicted state; its x [m] is used.

        Returns
        -------
        tuple of numpy.ndarray
            RRH positions [m, 2] [m], AODs [m] [rad] and TOAs [m] [s]
            (:meth:`MeasuredCandidates.pick`).
        """
        self._x = float(s[0])
        return self._setup.meas.pick(k + self._setup.k0, float(s[0]))

    def reacquire(self, k: int) -> tuple[NDArray, NDArray] | None:
        """The re-acquisition fix at filter epoch ``k`` (:data:`railradio.nr.tracking.ekf.Reacquire`):
        the snapshot fix around the position the last :meth:`select` was given.

        Parameters
        ----------
        k : int
            Filter epoch (the realization's epoch ``k + k0``).

        Returns
        -------
        tuple of numpy.ndarray, or None
            Position [2] [m] and covariance [2, 2] [m²] (:meth:`MeasuredCandidates.snapshot_fix`);
            None without the gate or without a fix.
        """
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
    its RRH at the predicted position (:func:`railradio.nr.channel.antenna.facing_panel`), whose along-track lever arm ℓ
    enters h(x) as an RRH shifted by -ℓ (on the straight track, x + ℓ - x_k = x - (x_k - ℓ); the Jacobian is
    unchanged). ``lever_arm=False`` ignores it: the source's point model [ours].

    Parameters
    ----------
    ds : xarray.Dataset
        One receiver's estimates, as for :func:`track`: ``rrh``, ``aod_hat`` [rad], ``toa_hat`` [s], the
        ``strength`` variable and, for the panels' lever arm, ``train_panel_x`` [m].
    rrh_x : numpy.ndarray
        Along-track positions of the RRHs, increasing, m.
    rrh_y : float
        Lateral offset of the RRHs from the track, m.
    dh_m : float
        RRH height above the train antenna, m.
    cfg : TrackerConfig
        The tracker settings (W of the snapshot fixes, the start's speed σ, the gate).
    strength : str
        Variable ranking the candidates (``"peak"``, ``"ss_rsrp"`` or ``"best_score"``).
    n_use : int
        Strongest measured candidates used per epoch.
    lever_arm : bool
        Model the head/tail panels' along-track lever arm (False: the source's point model).

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
    """Track one realization from a :func:`railradio.nr.engine.epochs.simulate_epochs` dataset.

    The first epoch with measurements gives the initial state (snapshot LS position, at
    rest: the source's trajectory starts from standstill) and P0 (its covariance; speed and
    acceleration standard deviations 1 m/s and 1 m/s² [ours]). Also returns (``snapshot``) the snapshot
    LS fix of every epoch (no tracking) as a baseline.

    Parameters
    ----------
    ds : xarray.Dataset
        One receiver's estimates (a :func:`railradio.nr.engine.epochs.simulate_epochs` dataset
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
        The tracker settings (measurement set, q, W, gate).
    strength : str
        Variable ranking the candidates (the receiver's selection): ``"peak"`` (combined
        correlation peak), ``"ss_rsrp"`` or ``"best_score"``.
    n_use : int
        Strongest measured candidates used per epoch.
    snapshot : bool
        Also compute the per-epoch snapshot LS fix.
    lever_arm : bool
        Model the head/tail panels' along-track lever arm (False: the source's point model).

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
