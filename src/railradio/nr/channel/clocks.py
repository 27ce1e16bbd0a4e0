"""Imperfect clocks of the RRHs and the train: per-RRH timing offsets and the train clock's
bias added to the measured TOAs [ours]."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

KEY_SYNC = 4
"""Sub-key of the clock offsets below a realization's spawn key (the simulation uses 1–3:
:data:`railradio.nr.engine.simulate.KEY_EPOCH` and its siblings)."""


def clock_offsets_s(seed: int, key: tuple[int, ...], rrh: NDArray, rrh_sigma_s: float) -> NDArray[np.float64]:
    """Timing offset [s] of each RRH in ``rrh`` against the network's time reference: one
    N(0, σ²) draw per realization and RRH, keyed (realization key, KEY_SYNC, RRH id), so
    an RRH keeps its offset along the whole run and whatever the sharding [ours].

    Parameters
    ----------
    seed : int
        The config seed.
    key : tuple of int
        The realization's spawn key (:func:`railradio.rng.spawn_key`).
    rrh : numpy.ndarray of int
        RRH ids, any shape (e.g. the candidates' ``rrh`` [epoch, cand]).
    rrh_sigma_s : float
        Standard deviation σ of the offsets [s]; >= 0 (0: no offsets).

    Returns
    -------
    numpy.ndarray
        Offset of each entry of ``rrh`` [s], same shape as ``rrh``.

    Raises
    ------
    ValueError
        When ``rrh_sigma_s`` is not >= 0 (negative or NaN).
    """
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

    Parameters
    ----------
    ds : xarray.Dataset
        Estimates (:func:`railradio.nr.engine.epochs.simulate_epochs`) with ``rrh`` (candidate RRH ids,
        dims (``epoch``, ``cand``)) and ``toa_hat`` [s].
    seed : int
        The config seed.
    key : tuple of int
        The realization's spawn key.
    rrh_sigma_s : float
        Standard deviation of the RRH timing offsets [s]; >= 0.
    train_bias_s : float
        The train clock's bias b [s]; finite.

    Returns
    -------
    xarray.Dataset
        A copy of ``ds`` with δ_k + b added to ``toa_hat`` [s] (its attributes kept), or ``ds``
        itself when both ``rrh_sigma_s`` and ``train_bias_s`` are 0.

    Raises
    ------
    ValueError
        When ``train_bias_s`` is not finite or ``rrh_sigma_s`` is not >= 0.
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
