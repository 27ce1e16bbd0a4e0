"""The tracker's view of one realization's candidates (docs/model/nr.md §5, Measured RRHs;
§6, Start, Gate and Baseline): which of an epoch's measured candidates it uses, chosen around
its predicted position, and the snapshot position fixes from them (the start, the
re-acquisition and the per-epoch baseline). It sees the estimates and the deployment, no
truth.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.channel.antenna import facing_panel
from railradio.nr.tracking.ekf import TrackerConfig
from railradio.nr.tracking.snapshot import snapshot_ls, snapshot_ls_batch


def anchor_x(cand_rrh: NDArray, cand_ok: NDArray, cand_strength: NDArray, rrh_x: NDArray) -> float:
    """Along-track position of the strongest cell with a measurement (AOD and TOA) among
    an epoch's candidates: where a receiver without a track places itself (the snapshot
    fix, the EKF's start); it sees only its measurements and the deployment, no truth.

    Parameters
    ----------
    cand_rrh : numpy.ndarray
        [cand] the candidates' RRH ids (indices into ``rrh_x``).
    cand_ok : numpy.ndarray
        [cand] whether each candidate has both an AOD and a TOA (bool).
    cand_strength : numpy.ndarray
        [cand] the selection strength (the receiver's ranking variable, any unit; larger is
        stronger; the first of equal maxima wins).
    rrh_x : numpy.ndarray
        [n_rrh] along-track positions of the RRHs, m.

    Returns
    -------
    float
        The strongest measured candidate's RRH position along the track, m; NaN when
        nothing was measured.
    """
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
    """Candidate columns to use at one epoch: among the measured candidates that are also
    among the ``n_nearest`` RRHs to the predicted position, the ``n_use`` strongest
    (source §4: the 3 strongest of the audible RRHs) [ours: the nearest-to-prediction rule].

    Parameters
    ----------
    cand_rrh : numpy.ndarray
        [cand] the candidates' RRH ids (indices into ``rrh_x``).
    cand_ok : numpy.ndarray
        [cand] whether each candidate has both an AOD and a TOA (bool).
    cand_strength : numpy.ndarray
        [cand] the selection strength (any unit; larger is stronger).
    rrh_x : numpy.ndarray
        [n_rrh] along-track positions of the RRHs, increasing, m.
    x_pred : float
        Predicted along-track position of the train, m (NaN or far off: a lost filter; the
        nearest RRHs are then ranked over all of them).
    n_nearest : int
        How many RRHs nearest to ``x_pred`` a used candidate must be among (ties: the lower
        RRH index first).
    n_use : int
        At most this many candidates are used.

    Returns
    -------
    numpy.ndarray
        [≤ n_use] candidate column indices (int64), strongest first; equal strengths keep
        the candidate order.
    """
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

    Attributes
    ----------
    rrh : numpy.ndarray
        [epoch, cand] the candidates' RRH ids (indices into ``rrh_x``).
    aod, toa : numpy.ndarray
        [epoch, cand] their estimated AODs, rad, and TOAs, s (NaN where not measured).
    ok : numpy.ndarray
        [epoch, cand] whether both the AOD and the TOA were measured (bool).
    strength : numpy.ndarray
        [epoch, cand] the selection strength (the receiver's ranking variable; -inf where
        none).
    rrh_x : numpy.ndarray
        [n_rrh] along-track positions of the RRHs, increasing, m.
    rrh_y : float
        Lateral offset of the RRHs from the track, m.
    dh_m : float
        Height difference between the RRHs and the train antenna, m.
    cfg : TrackerConfig
        The tracker settings (measurement set and W of the snapshot fixes).
    n_use : int
        RRHs used per epoch.
    panel_x : tuple of float
        Along-track lever arms ℓ of the head and tail panels, m ((0, 0): the point model).
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
        """Number of epochs.

        Returns
        -------
        int
            Rows of the candidate arrays.
        """
        return self.rrh.shape[0]

    def pick(self, k: int, x_pred: float) -> tuple[NDArray, NDArray, NDArray]:
        """Measurement selection at epoch ``k`` around the predicted along-track position
        (:func:`select_measurements`, the nearest RRHs counted as many as there are candidate
        columns).

        Parameters
        ----------
        k : int
            Epoch (row of the candidate arrays).
        x_pred : float
            Predicted along-track position of the train, m.

        Returns
        -------
        rrh_xy : numpy.ndarray
            [m, 2] positions (x, y) of the m ≤ ``n_use`` selected RRHs, m, strongest first;
            with separate panels each x is shifted by the lever arm of the panel facing that
            RRH at ``x_pred`` (:func:`railradio.nr.channel.antenna.facing_panel`); [0, 2] when none.
        aod : numpy.ndarray
            [m] their AODs, rad.
        toa : numpy.ndarray
            [m] their TOAs, s.
        """
        cols = select_measurements(
            self.rrh[k], self.ok[k], self.strength[k], self.rrh_x, x_pred, self.rrh.shape[1], self.n_use
        )
        x_k = self.rrh_x[self.rrh[k, cols]]
        if self.panel_x != (0.0, 0.0):  # lever arm of the panel facing each RRH
            x_k = x_k - np.asarray(self.panel_x)[facing_panel(x_pred, x_k, self.rrh_y, self.panel_x)]
        xy = np.stack([x_k, np.full(cols.size, self.rrh_y)], axis=1) if cols.size else np.zeros((0, 2))
        return xy, self.aod[k, cols], self.toa[k, cols]

    def snapshot_fix(self, k: int, x_pred: float) -> tuple[NDArray, NDArray] | None:
        """Snapshot LS fix (:func:`railradio.nr.tracking.snapshot.snapshot_ls`) from the measurements
        picked around ``x_pred`` (:meth:`pick`), started at the strongest one's own closed
        form x_k + ρ (cos θ, sin θ) (ρ the horizontal range from its TOA and ``dh_m``, at
        least 1 m).

        Parameters
        ----------
        k : int
            Epoch (row of the candidate arrays).
        x_pred : float
            Along-track position around which the measurements are picked, m.

        Returns
        -------
        tuple of numpy.ndarray, or None
            The position (x, y) [2], m, and its covariance [2, 2], m²; None when nothing is
            measured, the fix or its covariance is not finite, or the LS runs away (farther
            from the strongest RRH than its horizontal range plus 1 km).
        """
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
        """Snapshot LS fix of every epoch, without tracking (the baseline): each epoch's
        measurements are those picked around its strongest measured cell (:func:`anchor_x`,
        :meth:`pick`), and each fix starts from that cell's own AOD/TOA closed form
        x_k + ρ (cos θ, sin θ) (ρ the horizontal range); all epochs in one batch
        (:func:`railradio.nr.tracking.snapshot.snapshot_ls_batch`).

        Returns
        -------
        numpy.ndarray
            [epoch, 2] positions (x, y), m; NaN where nothing was measured. Unlike
            :meth:`snapshot_fix`, a fix that runs away is kept.
        """
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
