"""The nr study's tracked along-track position error as the handover's position input.

Source: ``results/nr/imm/{real}.nc`` (the nr IMM rule), variable ``along_err`` (x̂ − x along
the track, signed, [m]) of a causal tracker — by default ``ekf``, the source's EKF on the
robust receiver's gated AOD+TOA measurements, the tracker the nr IMM section reports (the
source receiver's tracks diverge; the track files ``results/nr/track/{real}.nc`` hold only
2-D error magnitudes, no sign).  Epochs without a detected RRH are coasted by the EKF's
prediction, so their error is already in ``along_err``; an epoch with no tracker output
(NaN) is an *outage*, filled by holding the last fix and letting the error grow by
dead reckoning at ``outage_drift_m_s`` (sign drawn per crossing).

Only epochs whose true speed is within ``speed_halfwidth_kmh`` of the handover speed are
used (tracker error depends on speed through the lag); they form contiguous *segments*.

Resampling (:func:`bootstrap`): a circular block bootstrap (Politis & Romano 1992) whose
block is one whole crossing: each crossing starts at a uniformly drawn epoch of the pooled
segments and a uniform phase within that epoch, and reads at the handover sample times the
latest tracker output (zero-order hold, the position the handover would have; the tracker's
velocity error times ≤ 100 ms is neglected), wrapping around within its segment.  Every
sample's marginal distribution is then exactly the pooled series' distribution, and the
error's time correlation over a crossing is the tracker's own.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr

from railradio.handover.params import KMH


@dataclass(frozen=True)
class ErrorSeries:
    """Pooled contiguous segments of the tracker's along-track error.

    Parameters
    ----------
    err_m : numpy.ndarray of float
        [E] error, outages already filled (hold + drift with sign +1), segments concatenated [m].
    drift_age_s : numpy.ndarray of float
        [E] time since the last fix (0 where the epoch has a fix) [s].
    starts, lengths : numpy.ndarray of int
        [S] first index into err_m and number of epochs of each segment.
    period_s : float
        tracker epoch period [s].
    outage_share : float
        share of the used epochs with no tracker output (NaN in the source) [1].
    drift_m_s : float
        dead-reckoning drift rate used to fill the outages [m/s].
    """

    err_m: np.ndarray
    drift_age_s: np.ndarray
    starts: np.ndarray
    lengths: np.ndarray
    period_s: float
    outage_share: float
    drift_m_s: float

    @property
    def n_epochs(self) -> int:
        """Number E of pooled epochs."""
        return int(self.err_m.size)


def _segments(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of the runs of True in ``mask``."""
    m = np.concatenate([[False], mask.astype(bool), [False]])
    d = np.diff(m.astype(np.int8))
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist(), strict=True))


def hold_and_drift(err_m: np.ndarray, period_s: float, drift_m_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Fill NaN epochs: last fix held plus drift·age (sign +1); (filled error, age [s]).

    The series must start with a fix (leading NaNs are cut by :func:`series_from_runs`).

    Parameters
    ----------
    err_m : numpy.ndarray of float
        [E] along-track error of one contiguous segment, one value per tracker epoch [m];
        NaN where the tracker has no output, the first value finite.
    period_s : float
        Tracker epoch period [s].
    drift_m_s : float
        Dead-reckoning drift rate during outages [m/s].

    Returns
    -------
    err_m : numpy.ndarray of float
        [E] the error with each NaN epoch replaced by the last fix plus ``drift_m_s`` times
        its age [m]; the fixes unchanged.
    age_s : numpy.ndarray of float
        [E] time since the last fix [s], 0 at an epoch with a fix.

    Raises
    ------
    ValueError
        If ``err_m`` is empty or its first value is not finite.
    """
    e = np.asarray(err_m, dtype=float)
    if e.size == 0 or not np.isfinite(e[0]):
        raise ValueError("err_m must start with a fix (a finite value)")
    idx = np.arange(e.size)
    last = np.maximum.accumulate(np.where(np.isfinite(e), idx, 0))
    age = (idx - last) * period_s
    return e[last] + drift_m_s * age, age


def series_from_runs(
    runs: Sequence[xr.Dataset], filt: str, speed_kmh: float, halfwidth_kmh: float, drift_m_s: float
) -> ErrorSeries:
    """Pool the along-track error of tracker ``filt`` over realizations ``runs`` (nr IMM
    datasets with ``along_err(filter, epoch)``, ``t``, ``x_true``), keeping the epochs whose
    true speed is within ``halfwidth_kmh`` of ``speed_kmh``.

    Parameters
    ----------
    runs : sequence of xarray.Dataset
        nr IMM datasets (``results/nr/imm/{real}.nc``), at least one, sharing one epoch period:
        ``along_err`` [m] over (filter, epoch), NaN where the tracker has no output;
        ``t`` [s] and ``x_true`` [m] over epoch.
    filt : str
        Tracker, a ``filter`` of the datasets (e.g. ``"ekf"``).
    speed_kmh : float
        Handover speed [km/h].
    halfwidth_kmh : float
        Half width of the speed window [km/h], > 0.
    drift_m_s : float
        Dead-reckoning drift during outages [m/s], >= 0.

    Returns
    -------
    ErrorSeries
        The pooled segments (each starting at its first fix, outages filled by hold + drift)
        with the outage share of the window's epochs.

    Raises
    ------
    ValueError
        If ``runs`` is empty, ``halfwidth_kmh`` <= 0, ``drift_m_s`` < 0, a dataset lacks
        ``along_err`` or the filter ``filt``, the datasets' epoch periods differ, or no epoch
        with a fix lies in the speed window.
    """
    if len(runs) == 0:
        raise ValueError("runs must hold at least one nr realization")
    if not halfwidth_kmh > 0:
        raise ValueError(f"halfwidth_kmh must be > 0, got {halfwidth_kmh!r}")
    if not drift_m_s >= 0:
        raise ValueError(f"drift_m_s must be >= 0, got {drift_m_s!r}")
    errs, ages, starts, lengths = [], [], [], []
    n_used = n_out = 0
    period = None
    for ds in runs:
        if "along_err" not in ds or filt not in ds["filter"].values:
            raise ValueError(f"filt must be a filter of the nr IMM file with along_err, got {filt!r}")
        t = ds["t"].values
        dt = float(np.median(np.diff(t)))
        if period is not None and not math.isclose(dt, period, rel_tol=1e-6):
            raise ValueError("runs must share one epoch period")
        period = dt
        e = ds["along_err"].sel(filter=filt).values.astype(float)
        for a, b in _segments(speed_mask(ds, speed_kmh, halfwidth_kmh)):
            seg = e[a:b]
            ok = np.flatnonzero(np.isfinite(seg))
            if ok.size == 0:
                n_used += seg.size
                n_out += seg.size
                continue
            n_used += seg.size
            n_out += int(np.sum(~np.isfinite(seg)))
            seg = seg[ok[0] :]  # a segment starts at its first fix
            f, age = hold_and_drift(seg, dt, drift_m_s)
            starts.append(sum(lengths))
            lengths.append(seg.size)
            errs.append(f)
            ages.append(age)
    if not lengths:
        raise ValueError(f"no nr epoch within ±{halfwidth_kmh} km/h of speed_kmh={speed_kmh}")
    return ErrorSeries(
        np.concatenate(errs),
        np.concatenate(ages),
        np.array(starts),
        np.array(lengths),
        float(period),
        n_out / n_used,
        float(drift_m_s),
    )


def bootstrap(
    series: ErrorSeries, n_runs: int, n_samples: int, sample_period_s: float, rng: np.random.Generator
) -> np.ndarray:
    """Along-track error [m] of ``n_runs`` crossings at ``n_samples`` handover samples,
    [n_runs, n_samples]: one circular block per crossing, zero-order hold (module doc).

    Parameters
    ----------
    series : ErrorSeries
        The pooled nr error (:func:`series_from_runs`).
    n_runs : int
        Crossings, >= 1.
    n_samples : int
        Handover samples per crossing, >= 1.
    sample_period_s : float
        Handover sample period [s], > 0.
    rng : numpy.random.Generator
        The block's generator (start epochs, phases, drift signs).

    Returns
    -------
    numpy.ndarray of float
        Signed along-track position error [m], shape [n_runs, n_samples]; outage epochs
        drift with a sign drawn per crossing.

    Raises
    ------
    ValueError
        If ``n_runs`` or ``n_samples`` < 1 or ``sample_period_s`` <= 0.
    """
    if n_runs < 1 or n_samples < 1:
        raise ValueError(f"n_runs and n_samples must be >= 1, got {n_runs!r}, {n_samples!r}")
    if not sample_period_s > 0:
        raise ValueError(f"sample_period_s must be > 0, got {sample_period_s!r}")
    u = rng.integers(0, series.n_epochs, size=n_runs)  # uniform over pooled epochs
    phase = rng.random(n_runs)  # position within the first epoch
    sign = np.where(rng.random(n_runs) < 0.5, -1.0, 1.0)  # drift sign during outages
    seg = np.searchsorted(series.starts, u, side="right") - 1
    start, length = series.starts[seg], series.lengths[seg]
    j = np.floor(phase[:, None] + np.arange(n_samples)[None, :] * (sample_period_s / series.period_s) + 1e-9).astype(
        np.int64
    )  # epochs elapsed (zero-order hold)
    idx = start[:, None] + ((u - start)[:, None] + j) % length[:, None]  # circular within the segment
    hold = series.err_m - series.drift_m_s * series.drift_age_s
    return hold[idx] + sign[:, None] * series.drift_m_s * series.drift_age_s[idx]


def error_stats(err_m: np.ndarray) -> dict[str, float]:
    """mean (signed), std, RMS and 95th percentile of |e| [m] of an error sample.

    Parameters
    ----------
    err_m : array_like of float
        Along-track position errors e [m], any shape; non-finite values are ignored.

    Returns
    -------
    dict of str to float
        ``mean`` (signed), ``std`` (population, ddof 0), ``rms`` and ``p95`` (95th
        percentile of |e|) [m] of the finite values.

    Raises
    ------
    ValueError
        If ``err_m`` holds no finite value.
    """
    e = np.asarray(err_m, dtype=float).ravel()
    e = e[np.isfinite(e)]
    if e.size == 0:
        raise ValueError("err_m must hold finite values")
    return {
        "mean": float(e.mean()),
        "std": float(e.std()),
        "rms": float(np.sqrt(np.mean(e * e))),
        "p95": float(np.percentile(np.abs(e), 95)),
    }


def speed_mask(ds: xr.Dataset, speed_kmh: float, halfwidth_kmh: float) -> np.ndarray:
    """bool [epoch]: true speed within ``halfwidth_kmh`` of ``speed_kmh``.

    Parameters
    ----------
    ds : xarray.Dataset
        An nr dataset (IMM or track file) with ``t`` [s] and the true along-track position
        ``x_true`` [m] over epoch.
    speed_kmh : float
        Centre of the speed window, the handover speed [km/h].
    halfwidth_kmh : float
        Half width of the speed window [km/h].

    Returns
    -------
    numpy.ndarray of bool
        Shape [epoch]: True where the true speed (the gradient of ``x_true`` over ``t``)
        differs from ``speed_kmh`` by at most ``halfwidth_kmh``.
    """
    t = ds["t"].values
    return np.abs(np.gradient(ds["x_true"].values, t) / KMH - speed_kmh) <= halfwidth_kmh


def nofix_share(tracks: Sequence[xr.Dataset], receiver: str, speed_kmh: float, halfwidth_kmh: float) -> float:
    """Share of the speed window's epochs in which ``receiver`` detected no RRH (neither an
    AOD nor a TOA), from the nr track files (``aod_err``/``range_err`` NaN when undetected).

    Parameters
    ----------
    tracks : sequence of xarray.Dataset
        nr track files (``results/nr/track/{real}.nc``): ``aod_err`` [rad] and ``range_err`` [m]
        over (receiver, epoch, slot), NaN where not detected; ``t`` [s] and ``x_true`` [m] over
        epoch.
    receiver : str
        A ``receiver`` of the track files.
    speed_kmh : float
        Handover speed [km/h].
    halfwidth_kmh : float
        Half width of the speed window [km/h].

    Returns
    -------
    float
        Share of the window's epochs, pooled over ``tracks``, without any detection [1], in
        [0, 1].

    Raises
    ------
    ValueError
        If ``receiver`` is not a receiver of a track file, or no epoch lies in the speed window.
    """
    n = k = 0
    for ds in tracks:
        if receiver not in ds["receiver"].values:
            raise ValueError(f"receiver must be one of {list(ds['receiver'].values)}, got {receiver!r}")
        m = speed_mask(ds, speed_kmh, halfwidth_kmh)
        a = ds["aod_err"].sel(receiver=receiver).values
        r = ds["range_err"].sel(receiver=receiver).values
        none = np.all(~np.isfinite(a), axis=-1) & np.all(~np.isfinite(r), axis=-1)
        n += int(m.sum())
        k += int(np.sum(none & m))
    if n == 0:
        raise ValueError(f"no nr epoch within ±{halfwidth_kmh} km/h of speed_kmh={speed_kmh}")
    return k / n


def nr_statistics(series: ErrorSeries, nofix: float) -> dict[str, float]:
    """Key statistics of the pooled nr error series (outages filled with drift sign +1).

    Parameters
    ----------
    series : ErrorSeries
        The pooled nr error (:func:`series_from_runs`).
    nofix : float
        Share of the window's epochs without any detected RRH (:func:`nofix_share`) [1].

    Returns
    -------
    dict of str to float
        ``mean`` (signed), ``std``, ``rms``, ``p95`` (95th percentile of |e|) [m] of
        ``series.err_m``; ``outage_share`` and ``nofix_share`` [1]; ``epochs`` (E, as float).

    Raises
    ------
    ValueError
        If ``series.err_m`` holds no finite value.
    """
    st = error_stats(series.err_m)
    st.update(
        {"outage_share": float(series.outage_share), "nofix_share": float(nofix), "epochs": float(series.n_epochs)}
    )
    return st
