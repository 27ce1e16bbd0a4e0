"""The handover's failure stages, one step each (``execution.failure_rule: stages``).

A handover is a sequence of procedures, and each can fail on its own link:

1. **Report → command** (TR 36.839 §5.2.1, TS 36.300 §10.1.2.1.1): the policy's decision is
   a measurement report; the handover command reaches the UE ``report_delay_s`` later (the
   network's preparation).
2. **Command reception** on the serving link: the command is lost when the serving link's
   T310 is running at that moment, or radio-link failure was already declared (TR 36.839
   §5.2.1's handover-failure rule); the failure is detected then (at the radio-link failure
   when that came first) and the UE re-establishes.
3. **Execution under T304** (TS 36.331 §5.3.5.4): after ``rrc_processing_s`` the UE tries
   random access at every PRACH occasion, ``ra_period_s`` apart, while T304 (``t304_s``)
   runs; access succeeds at the first occasion at which the target's SINR, with fast fading
   on both links (one look, :mod:`railradio.handover.fading`), is at least Q_out and
   completes ``t0_s − rrc_processing_s`` later (so T0 after the command when the first
   occasion succeeds). T304 expiry is a handover failure (TS 36.331 §5.3.5.6).
4. **Monitoring of the new link** (TS 36.300 §22.4.2.2): radio-link monitoring of the target
   starts afresh at completion (its windows filled from then on); a T310 started within
   ``monitor_s`` of completion that expires is a radio-link failure shortly after the
   handover.
5. **Classification** (TS 36.300 §22.4.2.2): after a failure the UE re-establishes in the
   stronger cell at that moment (the local means). Too late: the serving side failed
   (stage 2, or radio-link failure before the command) and the UE re-establishes in the
   target. Too early: access failed (stage 3) or the new link failed (stage 4) and the UE
   re-establishes in the source. Otherwise the failure is not a mobility failure (a
   re-establishment in the cell it failed in). With two cells a handover to a wrong cell
   cannot happen (its count is reported as 0 by construction). Ping-pong stays the
   policies' return rule.

Monitoring reads the links' local means (path loss and shadowing) on the radio-link
monitoring grid (:func:`railradio.handover.model.rlm_positions_m`): positions v·T_ind apart
along the track, which every node of a train passes; the one-shot tests (the PRACH
occasions, the re-establishment cell) read them at the node's own position.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray

from railradio.handover.radio import sinr_db
from railradio.handover.rlm import RlmConfig, indications, t310_step

SUCCESS, TOO_LATE, TOO_EARLY, WRONG_CELL, OTHER_RLF = 0, 1, 2, 3, 4
"""Outcome codes of one handover (``failure_kind``)."""

KIND_NAMES = {
    SUCCESS: "success",
    TOO_LATE: "too_late",
    TOO_EARLY: "too_early",
    WRONG_CELL: "wrong_cell",
    OTHER_RLF: "other_rlf",
}

STAGE_NONE, STAGE_COMMAND, STAGE_ACCESS, STAGE_NEW_LINK = 0, 1, 2, 3
"""Where a handover failed (``failure_stage``): nowhere, command reception (or an earlier
radio-link failure), access under T304, the new link's monitoring."""


@njit(cache=True, nogil=True)
def _t310_running(oos, ins, n310, n311, n_t310):  # pragma: no cover - compiled
    """Per row: T310 running after each indication (bool [R, J]) and the indication of the
    first radio-link failure (J: none); after it, ``running`` stays True."""
    rows, n_j = oos.shape
    running = np.zeros((rows, n_j), dtype=np.bool_)
    rlf = np.full(rows, n_j, dtype=np.int64)
    for r in range(rows):
        c_oos = 0
        c_in = 0
        start = -1
        for j in range(n_j):
            c_oos, c_in, start = t310_step(oos[r, j], ins[r, j], j, c_oos, c_in, start, n310, n311)
            running[r, j] = start >= 0
            if start >= 0 and j - start >= n_t310:
                rlf[r] = j
                for jj in range(j, n_j):
                    running[r, jj] = True
                break
    return running, rlf


@njit(cache=True, nogil=True)
def _rlf_after(oos, ins, row, j_first, j_last_start, n310, n311, n_t310):  # pragma: no cover - compiled
    """Per query q: radio-link monitoring of row ``row[q]`` started afresh at indication
    ``j_first[q]``; the indication at which a T310 started at or before ``j_last_start[q]``
    expires (-1: none)."""
    n_q = row.shape[0]
    n_j = oos.shape[1]
    out = np.full(n_q, -1, dtype=np.int64)
    for q in range(n_q):
        r = row[q]
        c_oos = 0
        c_in = 0
        start = -1
        for j in range(max(j_first[q], 0), n_j):
            if start < 0 and j > j_last_start[q]:
                break
            c_oos, c_in, start = t310_step(oos[r, j], ins[r, j], j, c_oos, c_in, start, n310, n311)
            if start >= 0 and j - start >= n_t310:
                out[q] = j
                break
    return out


@dataclass(frozen=True)
class StageTimes:
    """The procedure's times (s), from ``handover.execution``.

    Attributes
    ----------
    report_delay_s : float
        Measurement report to the command's reception.
    rrc_processing_s : float
        Command reception to the first PRACH occasion (the UE's RRC processing).
    t0_s : float
        Command to completion when the first occasion succeeds.
    ra_period_s : float
        Between two PRACH occasions.
    t304_s : float
        T304: the time access may take from the command.
    monitor_s : float
        A T310 started on the new link within this time of completion counts (stage 4).
    """

    report_delay_s: float
    rrc_processing_s: float
    t0_s: float
    ra_period_s: float
    t304_s: float
    monitor_s: float

    def __post_init__(self) -> None:
        if not 0.0 <= self.rrc_processing_s <= self.t0_s:
            raise ValueError(f"rrc_processing_s must be in [0, t0_s = {self.t0_s}] s, got {self.rrc_processing_s!r}")
        if not self.ra_period_s > 0.0:
            raise ValueError(f"ra_period_s must be > 0 s, got {self.ra_period_s!r}")
        if not self.t304_s >= self.rrc_processing_s:
            raise ValueError(f"t304_s must be >= rrc_processing_s, got {self.t304_s!r}")

    @property
    def n_occasions(self) -> int:
        """PRACH occasions while T304 runs: at rrc_processing + i·ra_period ≤ t304."""
        return int(np.floor((self.t304_s - self.rrc_processing_s) / self.ra_period_s + 1e-9)) + 1


@dataclass
class StageOutcome:
    """The stages' outcome of a set of handovers (flat arrays, one per handover)."""

    success: NDArray[np.bool_]
    completion_x_m: NDArray[np.float64]  # where access succeeded (NaN: never)
    occasions: NDArray[np.int64]  # PRACH occasions used (0: access not reached)
    kind: NDArray[np.int8]  # SUCCESS, TOO_LATE, ...
    stage: NDArray[np.int8]  # STAGE_*
    t_detect_s: NDArray[np.float64]  # failure detection after the command [s] (NaN: success)
    reestablish_target: NDArray[np.bool_]  # the failed handover re-establishes in the target
    t310_at_command: NDArray[np.bool_]  # the serving link's T310 ran at the command


class LinkMonitor:
    """Radio-link monitoring of both links of one block on the indication grid.

    Parameters
    ----------
    x_m : numpy.ndarray
        Indication positions along the track [m], [J] (equally spaced, J ≥ 2).
    means : callable
        ``means(run, x_m) -> (r_s_dbm, r_t_dbm)``: the local-mean received power of the
        serving and target links of crossings ``run`` at positions ``x_m`` [dBm]
        (:meth:`railradio.handover.model.BlockContext.true_rsrp_dbm`).
    n_runs : int
        Crossings B of the block.
    radio : railradio.handover.params.Radio
        The link parameters (noise, load, Q_out).
    cfg : RlmConfig
        The monitoring constants.
    """

    def __init__(self, x_m: NDArray, means, n_runs: int, radio, cfg: RlmConfig):
        self.x_m, self.means, self.radio, self.cfg = np.asarray(x_m, dtype=float), means, radio, cfg
        self.step_m = float(self.x_m[1] - self.x_m[0])
        r_s_dbm, r_t_dbm = means(np.arange(n_runs)[:, None], self.x_m[None, :])
        self.sinr_s = sinr_db(r_s_dbm, r_t_dbm, radio)
        self.sinr_t = sinr_db(r_t_dbm, r_s_dbm, radio)
        oos, ins = indications(self.sinr_s, cfg)
        self.t310_s, self.rlf_s = _t310_running(
            np.ascontiguousarray(oos), np.ascontiguousarray(ins), cfg.n310, cfg.n311, cfg.t310_indications
        )
        oos_t, ins_t = indications(self.sinr_t, cfg)
        self.oos_t, self.ins_t = np.ascontiguousarray(oos_t), np.ascontiguousarray(ins_t)

    def index_at(self, x_m: NDArray) -> NDArray[np.int64]:
        """The last indication at or before each position (−1: before the first)."""
        j = np.floor((np.asarray(x_m, dtype=float) - self.x_m[0]) / self.step_m + 1e-9).astype(np.int64)
        return np.minimum(j, self.x_m.size - 1)

    def rlf_x_m(self, run: NDArray) -> NDArray[np.float64]:
        """Where the serving link declares radio-link failure [m] (inf: never), per handover."""
        j = self.rlf_s[run]
        return np.where(j < self.x_m.size, self.x_m[np.minimum(j, self.x_m.size - 1)], np.inf)


def execute_stages(
    mon: LinkMonitor, st: StageTimes, run: NDArray, hb_m: NDArray, v_m_s: float, fading_db=None
) -> StageOutcome:
    """Stages 2–5 for handovers commanded at true positions ``hb_m`` (stage 1, the report
    delay, is in the command's position already).

    Parameters
    ----------
    mon : LinkMonitor
        Both links' monitoring on the block's indication grid.
    st : StageTimes
        The procedure's times.
    run : numpy.ndarray of int
        The crossing (row of ``mon``) of each handover.
    hb_m : numpy.ndarray
        True position of the node when the command reaches it [m].
    v_m_s : float
        Train speed [m/s].
    fading_db : tuple of numpy.ndarray, optional
        Fast-fading power gains [dB] of the serving and target link at each handover's PRACH
        occasions, each [n, occasions] (:func:`railradio.handover.model.access_fading_db`);
        ``None``: local means only.

    Returns
    -------
    StageOutcome
        Per handover: success, completion position, occasions used, outcome class, failed
        stage, detection time after the command, re-establishment cell, T310 at the command.
    """
    run = np.asarray(run, dtype=np.int64)
    hb = np.asarray(hb_m, dtype=float)
    n = hb.size
    cfg, radio = mon.cfg, mon.radio
    # stage 2: the command on the serving link
    j_cmd = mon.index_at(hb)
    t310 = np.where(j_cmd >= 0, mon.t310_s[run, np.maximum(j_cmd, 0)], False)
    x_rlf = mon.rlf_x_m(run)
    lost = t310 | (x_rlf <= hb)
    # stage 3: access at the PRACH occasions while T304 runs (first at or above Q_out)
    i_occ = np.arange(st.n_occasions)
    x_occ = hb[:, None] + v_m_s * (st.rrc_processing_s + st.ra_period_s * i_occ)[None, :]
    r_s, r_t = mon.means(run[:, None], x_occ)
    if fading_db is not None:  # one look per occasion: fast fading on both links
        r_s, r_t = r_s + fading_db[0], r_t + fading_db[1]
    ok = sinr_db(r_t, r_s, radio) >= radio.q_out_db
    first = np.where(ok.any(axis=1), np.argmax(ok, axis=1), -1)
    accessed = ~lost & (first >= 0)
    t_access = st.rrc_processing_s + st.ra_period_s * np.maximum(first, 0)
    x_done = np.where(accessed, hb + v_m_s * (t_access + st.t0_s - st.rrc_processing_s), np.nan)
    # stage 4: the new link's monitoring, afresh from completion
    j_done = np.where(accessed, np.ceil((np.nan_to_num(x_done) - mon.x_m[0]) / mon.step_m - 1e-9), 0).astype(np.int64)
    j_first = j_done + cfg.samples(cfg.qout_eval_s) - 1  # the first full Q_out window after completion
    j_last = j_done + int(round(st.monitor_s / cfg.indication_s))
    sel = np.flatnonzero(accessed)
    j_rlf_t = np.full(n, -1, dtype=np.int64)
    if sel.size:
        j_rlf_t[sel] = _rlf_after(mon.oos_t, mon.ins_t, run[sel], j_first[sel], j_last[sel], *_counts(cfg))
    new_link_rlf = j_rlf_t >= 0
    success = accessed & ~new_link_rlf
    # when each failure is detected (s after the command) and where the UE re-establishes
    t_detect = np.full(n, np.nan)
    t_detect[lost] = np.minimum((x_rlf[lost] - hb[lost]) / v_m_s, 0.0)  # at the command, or the earlier RLF
    no_access = ~lost & ~accessed
    t_detect[no_access] = st.t304_s
    t_detect[new_link_rlf] = (mon.x_m[np.maximum(j_rlf_t[new_link_rlf], 0)] - hb[new_link_rlf]) / v_m_s
    fail = ~success
    x_fail = hb + v_m_s * np.nan_to_num(t_detect)
    fs, ft = mon.means(run, x_fail)
    to_target = fail & (ft > fs)
    stage = np.full(n, STAGE_NONE, dtype=np.int8)
    stage[lost] = STAGE_COMMAND
    stage[no_access] = STAGE_ACCESS
    stage[new_link_rlf] = STAGE_NEW_LINK
    kind = np.full(n, SUCCESS, dtype=np.int8)
    kind[lost] = np.where(to_target[lost], TOO_LATE, OTHER_RLF)
    early = no_access | new_link_rlf
    kind[early] = np.where(to_target[early], OTHER_RLF, TOO_EARLY)
    return StageOutcome(
        success,
        x_done,
        np.where(accessed, first + 1, np.where(no_access, st.n_occasions, 0)).astype(np.int64),
        kind,
        stage,
        t_detect,
        to_target,
        t310,
    )


def _counts(cfg: RlmConfig) -> tuple[int, int, int]:
    return int(cfg.n310), int(cfg.n311), cfg.t310_indications
