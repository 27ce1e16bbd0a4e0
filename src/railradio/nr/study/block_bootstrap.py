"""The moving-block bootstrap of the reproduction map (railradio.nr.study.reproduction_map):
resamples of a segment's epochs in blocks, so that errors correlated along the track (over
an RRH spacing) keep their correlation in each resample (Künsch 1989, Ann. Statist. 17(3)),
and the percentiles of resampled metrics that may hold no value.
"""

from __future__ import annotations

import warnings

import numpy as np


def block_indices(rng: np.random.Generator, n: int, block: int, n_boot: int) -> np.ndarray:
    """Moving-block-bootstrap resamples of ``n`` epochs: [n_boot, n] indices, each row
    ⌈n/block⌉ blocks of ``block`` consecutive epochs with uniform starts, cut to n.

    Parameters
    ----------
    rng : numpy.random.Generator
        Generator of the block starts.
    n, block, n_boot : int
        Epochs, block length [epochs] (in 1..n) and resamples (≥ 1).

    Returns
    -------
    numpy.ndarray of int
        [n_boot, n] epoch indices.

    Raises
    ------
    ValueError
        When ``block`` is outside 1..n or ``n_boot`` < 1.
    """
    if not 1 <= block <= n:
        raise ValueError(f"block must be in 1..n={n}, got {block!r}")
    if n_boot < 1:
        raise ValueError(f"n_boot must be >= 1, got {n_boot!r}")
    k = -(-n // block)
    starts = rng.integers(0, n - block + 1, size=(n_boot, k))
    return (starts[:, :, None] + np.arange(block)).reshape(n_boot, -1)[:, :n]


def nanpercentile(x: np.ndarray, q: float) -> np.ndarray:
    """q-th percentile along the last axis, ignoring NaN (NaN where nothing is finite).

    Parameters
    ----------
    x : numpy.ndarray
        Values; the percentile is taken along the last axis.
    q : float
        Percentile, in [0, 100].

    Returns
    -------
    numpy.ndarray
        ``x``'s shape without its last axis.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # "All-NaN slice": NaN is the answer
        return np.nanpercentile(x, q, axis=-1)
