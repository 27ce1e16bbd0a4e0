"""Lost tracks reported as lost: the share of epochs a tracker has lost and when it lost
them, and accuracy only where it means something.

An epoch is **lost** when the 2-D position error exceeds half the RRH spacing: beyond it
the nearest RRH to the estimate is another one than to the train, so the tracker's
measurement association is wrong and the error no longer says how accurate a tracker is —
a filter that diverges to 10¹⁹ m has no "mean error". An epoch without a position (NaN) is
lost too.

Reported per tracker (receiver × measurement set × gate):

* ``lost_frac``: the share of the scored epochs (after the first ``SKIP_S`` seconds) lost;
* ``time_to_loss_s``: time from the run's start to its first lost epoch (the mean over the
  realizations that lose the track; null when none does);
* ``tracked.err_m.*``: accuracy over the epochs not lost;
* ``err_m.*``: accuracy over all scored epochs — only where the lost share is below
  :data:`LOST_FRAC_MAX` and the value below :data:`ACCURACY_CAP_M`; otherwise null, with the
  lost share beside it (the manuscript prints "lost (x % of epochs)").
"""

from __future__ import annotations

import json

import numpy as np
import xarray as xr
from numpy.typing import NDArray

LOST_FRAC_MAX = 0.01
"""All-epoch accuracy is reported only below this lost share."""
ACCURACY_CAP_M = 10_000.0
"""No accuracy key above this [m]: such a value describes a loss, not an accuracy."""


def rrh_spacing_m(ds: xr.Dataset) -> float:
    """The RRH spacing [m] of the deployment that made a track dataset (its provenance).

    Parameters
    ----------
    ds : xarray.Dataset
        A track or IMM dataset whose ``config_json`` attribute holds ``sim.deployment.spacing_m``.

    Returns
    -------
    float
        The RRH spacing, m.

    Raises
    ------
    ValueError
        When the attribute is missing or does not name the spacing.
    """
    try:
        return float(json.loads(ds.attrs["config_json"])["sim"]["deployment"]["spacing_m"])
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(
            "the track dataset names no deployment spacing in its config_json attribute (sim.deployment.spacing_m)"
        ) from exc


def lost_mask(err_m: NDArray[np.float64], spacing_m: float) -> NDArray[np.bool_]:
    """Epochs whose 2-D error exceeds half the RRH spacing, or that have no position.

    Parameters
    ----------
    err_m : numpy.ndarray
        2-D position errors [m], any shape; NaN: no position.
    spacing_m : float
        RRH spacing [m]; > 0.

    Returns
    -------
    numpy.ndarray of bool
        True where lost (error > spacing_m / 2 or NaN), the shape of ``err_m``.

    Raises
    ------
    ValueError
        When ``spacing_m`` <= 0.
    """
    if not spacing_m > 0:
        raise ValueError(f"spacing_m must be > 0, got {spacing_m!r}")
    err_m = np.asarray(err_m, dtype=float)
    return ~(err_m <= spacing_m / 2)


def time_to_loss_s(runs: list[tuple[NDArray, NDArray]], spacing_m: float) -> float | None:
    """Mean over the runs ``(t [s], err [m])`` that lose the track of the time of their first
    lost epoch; None when no run loses it.

    Parameters
    ----------
    runs : list of tuple of numpy.ndarray
        Per run ``(t, err)``: epoch times [s] and 2-D position errors [m], each [T].
    spacing_m : float
        RRH spacing [m] (:func:`lost_mask`).

    Returns
    -------
    float or None
        Mean time of the first lost epoch over the runs that lose the track [s].
    """
    firsts = []
    for t, err in runs:
        lost = lost_mask(err, spacing_m)
        if lost.any():
            firsts.append(float(np.asarray(t)[np.argmax(lost)]))
    return float(np.mean(firsts)) if firsts else None


def accuracy(value: float | None, lost_frac: float) -> float | None:
    """An all-epoch accuracy as reported: None when the track is lost too often
    (``lost_frac >= LOST_FRAC_MAX``), the value is not finite, or it exceeds the cap.

    Parameters
    ----------
    value : float or None
        The all-epoch accuracy statistic [m].
    lost_frac : float
        Share of the scored epochs lost, in [0, 1].

    Returns
    -------
    float or None
        ``value`` [m], or None (see above).
    """
    if value is None or not np.isfinite(value) or lost_frac >= LOST_FRAC_MAX or value > ACCURACY_CAP_M:
        return None
    return float(value)
