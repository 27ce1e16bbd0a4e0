"""Radio-link monitoring and radio-link failure as 3GPP defines them.

Physical layer (TS 36.213 §4.2.1; requirements TS 36.133 §7.6, non-DRX): an indication
every 10 ms; *out-of-sync* when the link quality estimated over the last 200 ms is worse
than Q_out, *in-sync* when the estimate over the last 100 ms is better than Q_in. Q_out and
Q_in are defined as the SINR of a 10 % and a 2 % hypothetical-PDCCH block error rate; the
SINR values used for them (−8 / −6 dB) are TR 36.839's mapping [3GPP, TR 36.839].

RRC (TS 36.331 §5.3.11): N310 consecutive out-of-sync indications start T310; N311
consecutive in-sync indications while T310 runs stop it; radio-link failure when T310
expires. Defaults N310 = N311 = 1, T310 = 1 s (TS 36.331 §9.2.5 default values, a common
network setting for T310).

Readings [ours]: the link quality over a window is the mean of the SINR in dB over the
window's indications (the hypothetical-BLER mapping is monotone, and at these SINRs the mean
in dB and the BLER-averaged reading rank windows alike to first order); no indication is
made before a full window exists; an indication that is out-of-sync is not also counted as
in-sync (a 100 ms mean above Q_in with a 200 ms mean below Q_out); T310 expires at the
indication T310 after the one that started it, and that indication may still stop it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray


@dataclass(frozen=True)
class RlmConfig:
    """Radio-link monitoring constants (SI units).

    Parameters
    ----------
    indication_s
        Interval between indications [s] (TS 36.213 §4.2.1: 10 ms).
    qout_eval_s, qin_eval_s
        Evaluation periods of the out-of-sync and in-sync tests [s] (TS 36.133 §7.6:
        200 ms and 100 ms).
    q_out_db, q_in_db
        Thresholds [dB SINR] (TR 36.839: −8 and −6 dB).
    n310, n311
        Consecutive out-of-sync / in-sync indications (TS 36.331 §9.2.5: 1 and 1).
    t310_s
        T310 [s] (TS 36.331 §9.2.5: 1 s).
    """

    indication_s: float = 0.010
    qout_eval_s: float = 0.200
    qin_eval_s: float = 0.100
    q_out_db: float = -8.0
    q_in_db: float = -6.0
    n310: int = 1
    n311: int = 1
    t310_s: float = 1.0

    def __post_init__(self) -> None:
        for name in ("indication_s", "qout_eval_s", "qin_eval_s"):
            if not 0.0 < getattr(self, name) <= 10.0:
                raise ValueError(f"{name} must be in (0, 10] s, got {getattr(self, name)!r}")
        if not 0.0 <= self.t310_s <= 10.0:
            raise ValueError(f"t310_s must be in [0, 10] s, got {self.t310_s!r}")
        for name in ("n310", "n311"):
            v = getattr(self, name)
            if not isinstance(v, (int, np.integer)) or not 1 <= v <= 20:
                raise ValueError(f"{name} must be an integer in 1..20 (TS 36.331 §6.3.6), got {v!r}")
        if not self.q_in_db > self.q_out_db:
            raise ValueError(f"q_in_db must exceed q_out_db, got {self.q_in_db!r} <= {self.q_out_db!r}")

    def samples(self, seconds: float) -> int:
        """A duration as a number of indications (at least one)."""
        return max(1, int(round(seconds / self.indication_s)))

    @property
    def t310_indications(self) -> int:
        """T310 in indications (zero allowed: failure at the indication that starts it)."""
        return int(round(self.t310_s / self.indication_s))


def indications(sinr_db: NDArray, cfg: RlmConfig) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """Out-of-sync and in-sync indications from SINR samples taken every ``indication_s``.

    ``sinr_db`` [..., J]: the link's SINR at each indication instant [dB]. Returns
    ``(oos, ins)`` bool [..., J]: the mean over the last ``qout_eval_s`` below Q_out, and the
    mean over the last ``qin_eval_s`` above Q_in (False until the window is full).
    """
    s = np.asarray(sinr_db, dtype=float)
    c = np.concatenate([np.zeros(s.shape[:-1] + (1,)), np.cumsum(s, axis=-1)], axis=-1)

    def mean_last(n: int) -> NDArray:
        out = np.full(s.shape, np.nan)
        if n <= s.shape[-1]:
            out[..., n - 1 :] = (c[..., n:] - c[..., :-n]) / n
        return out

    with np.errstate(invalid="ignore"):
        oos = mean_last(cfg.samples(cfg.qout_eval_s)) < cfg.q_out_db
        ins = (mean_last(cfg.samples(cfg.qin_eval_s)) > cfg.q_in_db) & ~oos
    return oos, ins


@njit(cache=True, nogil=True)
def t310_step(oos_j, ins_j, j, c_oos, c_in, start, n310, n311):  # pragma: no cover - compiled
    """One indication j of TS 36.331 §5.3.11: N310 consecutive out-of-sync start T310 (its
    start indication, −1 while stopped), N311 consecutive in-sync stop it. Returns the new
    (out-of-sync count, in-sync count, start)."""
    if start < 0:
        c_oos = c_oos + 1 if oos_j else 0
        if c_oos >= n310:
            start, c_in = j, 0
    else:
        c_in = c_in + 1 if ins_j else 0
        if c_in >= n311:
            start, c_oos = -1, 0
    return c_oos, c_in, start


@njit(cache=True, nogil=True)
def _first_rlf(oos, ins, n310, n311, n_t310):  # pragma: no cover - compiled
    rows, n_j = oos.shape
    out = np.full(rows, n_j, dtype=np.int64)
    for r in range(rows):
        c_oos = 0
        c_in = 0
        start = -1
        for j in range(n_j):
            c_oos, c_in, start = t310_step(oos[r, j], ins[r, j], j, c_oos, c_in, start, n310, n311)
            if start >= 0 and j - start >= n_t310:
                out[r] = j
                break
    return out


def first_rlf(oos: NDArray[np.bool_], ins: NDArray[np.bool_], cfg: RlmConfig) -> NDArray[np.int64]:
    """Index of the indication at which radio-link failure is declared, per row of
    ``oos``/``ins`` [..., J] (J where none): the N310/N311/T310 procedure of TS 36.331
    §5.3.11 started with T310 stopped and both counters at zero."""
    oos = np.asarray(oos, dtype=np.bool_)
    ins = np.asarray(ins, dtype=np.bool_)
    if oos.shape != ins.shape:
        raise ValueError(f"oos and ins must have one shape, got {oos.shape} and {ins.shape}")
    flat_o = np.ascontiguousarray(oos.reshape(-1, oos.shape[-1]))
    flat_i = np.ascontiguousarray(ins.reshape(-1, ins.shape[-1]))
    out = _first_rlf(flat_o, flat_i, int(cfg.n310), int(cfg.n311), cfg.t310_indications)
    return out.reshape(oos.shape[:-1])


def first_rlf_reference(oos, ins, cfg: RlmConfig) -> int:
    """:func:`first_rlf` for one row, written as the procedure reads (a test reference)."""
    n_t310 = cfg.t310_indications
    counter_oos = counter_in = 0
    t310_started_at = None
    for j, (o, i) in enumerate(zip(oos, ins, strict=True)):
        if t310_started_at is None:  # T310 stopped: count consecutive out-of-sync
            counter_oos = counter_oos + 1 if o else 0
            if counter_oos >= cfg.n310:
                t310_started_at, counter_in = j, 0
        else:  # T310 running: count consecutive in-sync
            counter_in = counter_in + 1 if i else 0
            if counter_in >= cfg.n311:
                t310_started_at, counter_oos = None, 0
        if t310_started_at is not None and j - t310_started_at >= n_t310:
            return j
    return len(oos)
