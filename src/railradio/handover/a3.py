"""The A3 event of TS 36.331 §5.5.4.4 and its time-to-trigger, vectorized.

Entering condition (A3-1): Mn + Ofn + Ocn − Hys > Mp + Ofp + Ocp + Off.
Leaving condition (A3-2):  Mn + Ofn + Ocn + Hys < Mp + Ofp + Ocp + Off.
Mn, Mp: neighbour and SpCell measurement results (after L3 filtering) [dBm];
Ofn/Ofp: frequency-specific offsets, Ocn/Ocp: cell-specific offsets, Hys: hysteresis,
Off: the event offset a3-Offset [dB].
"""

from __future__ import annotations

import math

import numpy as np


def a3_entering(
    mn,
    mp,
    hys_db: float,
    off_db: float = 0.0,
    ofn_db: float = 0.0,
    ocn_db: float = 0.0,
    ofp_db: float = 0.0,
    ocp_db: float = 0.0,
) -> np.ndarray:
    """Entering condition A3-1 (TS 36.331 §5.5.4.4), elementwise."""
    return np.asarray(mn) + ofn_db + ocn_db - hys_db > np.asarray(mp) + ofp_db + ocp_db + off_db


def a3_leaving(
    mn,
    mp,
    hys_db: float,
    off_db: float = 0.0,
    ofn_db: float = 0.0,
    ocn_db: float = 0.0,
    ofp_db: float = 0.0,
    ocp_db: float = 0.0,
) -> np.ndarray:
    """Leaving condition A3-2 (TS 36.331 §5.5.4.4), elementwise."""
    return np.asarray(mn) + ofn_db + ocn_db + hys_db < np.asarray(mp) + ofp_db + ocp_db + off_db


def ttt_samples(ttt_s: float, period_s: float) -> int:
    """Consecutive samples over which a condition must hold to last ``ttt_s``.

    The timer starts at the first sample that meets the condition and the event triggers
    at the first sample at least TTT later, the condition met at every sample in between:
    n = ceil(TTT/T_m) + 1 (TTT = 0: the first sample).
    """
    if ttt_s < 0 or period_s <= 0:
        raise ValueError(f"ttt_s must be >= 0 and period_s > 0, got {ttt_s!r}, {period_s!r}")
    return int(math.ceil(ttt_s / period_s - 1e-9)) + 1


def run_length(cond: np.ndarray) -> np.ndarray:
    """Number of consecutive True values ending at each sample (last axis), 0 where False."""
    cond = np.asarray(cond, dtype=bool)
    k = np.arange(cond.shape[-1])
    last_false = np.where(cond, -1, k)
    last_false = np.maximum.accumulate(last_false, axis=-1)
    return np.where(cond, k - last_false, 0)


def first_true(mask: np.ndarray, default: int = -1) -> np.ndarray:
    """Index of the first True along the last axis, ``default`` where there is none."""
    mask = np.asarray(mask, dtype=bool)
    idx = np.argmax(mask, axis=-1)
    return np.where(mask.any(axis=-1), idx, default)


def held_for(cond: np.ndarray, n: int) -> np.ndarray:
    """bool: ``cond`` held at this sample and the n − 1 before it (last axis)."""
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n!r}")
    c = np.cumsum(np.asarray(cond, dtype=np.int32), axis=-1, dtype=np.int32)
    out = c >= n
    out[..., n:] = (c[..., n:] - c[..., :-n]) == n
    return out
