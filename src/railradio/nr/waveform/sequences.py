"""NR primary and secondary synchronization sequences (TS 38.211 v17 §7.4.2.2–7.4.2.3)."""

from __future__ import annotations

from functools import cache

import numpy as np
from numpy.typing import NDArray

N_ID1_MAX = 335
N_ID2_MAX = 2
SEQ_LEN = 127


def _m_sequence(init: list[int], taps: tuple[int, int]) -> NDArray[np.int64]:
    """x(i+7) = (x(i+taps[0]) + x(i+taps[1])) mod 2 with x(0..6) = init, length 127."""
    x = np.zeros(SEQ_LEN, dtype=np.int64)
    x[:7] = init
    for i in range(SEQ_LEN - 7):
        x[i + 7] = (x[i + taps[0]] + x[i + taps[1]]) % 2
    return x


@cache
def _pss_x() -> NDArray[np.int64]:
    # TS 38.211 prints [x(6) ... x(0)] = [1 1 1 0 1 1 0]
    return _m_sequence([0, 1, 1, 0, 1, 1, 1], (4, 0))


@cache
def _sss_x() -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    init = [1, 0, 0, 0, 0, 0, 0]
    return _m_sequence(init, (4, 0)), _m_sequence(init, (1, 0))


def pss(n_id2: int) -> NDArray[np.int64]:
    """PSS d_PSS(n) = 1 - 2 x((n + 43 N_ID2) mod 127), n = 0..126, values ±1.

    Parameters
    ----------
    n_id2 : int
        N_ID^(2), 0..2.

    Returns
    -------
    numpy.ndarray of int64
        The sequence, ±1: [127].

    Raises
    ------
    ValueError
        If ``n_id2`` is not in {0, 1, 2}.
    """
    if n_id2 not in (0, 1, 2):
        raise ValueError(f"n_id2 must be 0, 1 or 2, got {n_id2!r}")
    n = np.arange(SEQ_LEN)
    return 1 - 2 * _pss_x()[(n + 43 * n_id2) % SEQ_LEN]


def sss(n_id1: int, n_id2: int) -> NDArray[np.int64]:
    """SSS d_SSS(n) = [1 - 2 x0((n + m0) mod 127)][1 - 2 x1((n + m1) mod 127)], ±1.

    m0 = 15 floor(N_ID1 / 112) + 5 N_ID2, m1 = N_ID1 mod 112.

    Parameters
    ----------
    n_id1 : int
        N_ID^(1), 0..335 (an integer type).
    n_id2 : int
        N_ID^(2), 0..2.

    Returns
    -------
    numpy.ndarray of int64
        The sequence, ±1: [127].

    Raises
    ------
    ValueError
        If ``n_id1`` is not in 0..335 or ``n_id2`` not in {0, 1, 2}.
    """
    if not (isinstance(n_id1, (int, np.integer)) and 0 <= n_id1 <= N_ID1_MAX):
        raise ValueError(f"n_id1 must be an integer in 0..335, got {n_id1!r}")
    if n_id2 not in (0, 1, 2):
        raise ValueError(f"n_id2 must be 0, 1 or 2, got {n_id2!r}")
    x0, x1 = _sss_x()
    m0 = 15 * (n_id1 // 112) + 5 * n_id2
    m1 = n_id1 % 112
    n = np.arange(SEQ_LEN)
    return (1 - 2 * x0[(n + m0) % SEQ_LEN]) * (1 - 2 * x1[(n + m1) % SEQ_LEN])


def pci(n_id1: int, n_id2: int) -> int:
    """Physical cell ID N_ID^cell = 3 N_ID1 + N_ID2.

    Parameters
    ----------
    n_id1 : int or numpy.ndarray of int
        N_ID^(1) (not checked).
    n_id2 : int or numpy.ndarray of int
        N_ID^(2) (not checked); broadcast against ``n_id1``.

    Returns
    -------
    int or numpy.ndarray of int
        The PCI, the broadcast shape of the inputs.
    """
    return 3 * n_id1 + n_id2
