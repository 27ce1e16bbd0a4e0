"""Key numbers ``nr.track.{ekf,imm,rts}.*`` and the figure ``nr_imm_lag`` of the
tracking-that-does-not-lag study (docs/model/nr.md §6): the gated EKF (the source's
eq. 10–14 on the robust receiver's measurements, with our χ² gate), the IMM and the RTS
smoother around the trajectory's acceleration changes.

The lag is measured two ways over the ``window_s`` after each change (all changes and
realizations pooled):

- ``err_m.after_change_mean``: mean 2-D position error;
- ``lag_m.after_change_mean``: mean along-track error signed so that a filter still
  extrapolating the old acceleration counts positive, −sign(Δa)·(x̂ − x) [ours]. Noise
  averages out of it; the bias a lagging filter builds up does not.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
import xarray as xr
from numpy.typing import NDArray

from railradio import plotting
from railradio.keynumbers import KeySpec
from railradio.nr.study.keys import SKIP_S
from railradio.nr.tracking import loss

FILTERS = ("ekf", "imm", "rts")
LABEL = {
    "ekf": "EKF (source, calibrated q)",
    "imm": "IMM (quiet + manoeuvre)",
    "rts": "RTS smoother (offline, over the EKF)",
}


def change_windows(
    ds: xr.Dataset, window_s: float, before_s: float = 0.0
) -> list[tuple[int, NDArray[np.int64], float]]:
    """(change epoch, epoch indices from ``before_s`` before to ``window_s`` after it
    (clipped to the run), Δa [m/s²]) of every acceleration change inside the run.

    Parameters
    ----------
    ds : xarray.Dataset
        One realization's IMM dataset (``t`` [s], ``change_epoch``, ``delta_a`` [m/s²]).
    window_s : float
        Window after each change, s (> 0).
    before_s : float
        Window before each change, s (≥ 0).

    Returns
    -------
    list of tuple
        ``(change epoch, epoch indices, Δa [m/s²])`` per change.

    Raises
    ------
    ValueError
        When ``window_s`` ≤ 0 or ``before_s`` < 0.
    """
    if not window_s > 0 or before_s < 0:
        raise ValueError(f"window_s must be > 0 and before_s >= 0 [s], got {window_s!r}, {before_s!r}")
    dt = float(ds["t"].values[1] - ds["t"].values[0]) if ds.sizes["epoch"] > 1 else 1.0
    n = ds.sizes["epoch"]
    out = []
    for c, da in zip(ds["change_epoch"].values, ds["delta_a"].values, strict=True):
        lo = int(c) - int(round(before_s / dt))
        idx = np.arange(max(lo, 0), min(int(c) + int(round(window_s / dt)), n))
        out.append((int(c), idx, float(da)))
    return out


def _pooled(runs: list[xr.Dataset], fn) -> tuple[float | None, float | None]:
    """Value pooled over all realizations and its standard error from their spread (as
    :func:`railradio.nr.study.keys._per_real`); None where no epoch qualifies."""
    pooled = fn(runs)
    if pooled is None or not np.isfinite(pooled):
        return None, None
    if len(runs) < 2:
        return float(pooled), None
    each = np.array([fn([r]) for r in runs], dtype=float)
    return float(pooled), float(np.std(each, ddof=1) / np.sqrt(len(runs)))


def _after(runs, var, filt, window_s, signed=False):
    vals = []
    for r in runs:
        v = r[var].sel(filter=filt).values if filt is not None else r[var].sel(mode="manoeuvre").values
        for c, idx, da in change_windows(r, window_s):
            w = v[idx[idx >= c]]
            vals.append(-np.sign(da) * w if signed else w)
    return np.concatenate(vals) if vals else np.array([])


def _overall(runs, var, filt):
    return np.concatenate([r[var].sel(filter=filt).values[r["t"].values >= SKIP_S] for r in runs])


def _stat(values: np.ndarray, how) -> float | None:
    v = values[np.isfinite(values)]
    return float(how(v)) if v.size else None


def key_numbers(runs: list[xr.Dataset], window_s: float) -> dict[str, Any]:
    """Key numbers of the IMM/RTS study, pooled over the realizations ``runs`` (datasets
    written by the ``nr_imm`` rule), errors counted after the first SKIP_S seconds.

    Parameters
    ----------
    runs : list of xarray.Dataset
        The realizations' IMM datasets (:func:`railradio.nr.study.runs.track_imm`), all from one RRH
        spacing.
    window_s : float
        Window after each acceleration change over which the lag is measured, s.

    Returns
    -------
    dict of str to dict
        Key name -> its JSON entry (:meth:`railradio.keynumbers.KeySpec.entry`: ``value``,
        ``unit``, ``description``, source value and relation, ``mc_stderr``, optional ``lost_frac``).

    Raises
    ------
    ValueError
        When ``runs`` is empty or its runs come from different RRH spacings.
    """
    if not runs:
        raise ValueError("runs must not be empty")
    w = f"{window_s:g} s"
    out: dict[str, Any] = {}
    spacings = {loss.rrh_spacing_m(r) for r in runs}
    if len(spacings) != 1:
        raise ValueError(f"runs come from different RRH spacings: {sorted(spacings)}")
    spacing = spacings.pop()
    for f in FILTERS:
        _filter_keys(out, runs, f, window_s, spacing)
    for mode in ("quiet", "manoeuvre"):
        name = f"nr.track.imm.q_{mode}"
        q = {float(r["q"].sel(mode=mode)) for r in runs}
        if len(q) != 1:
            raise ValueError(f"runs disagree on the {mode} model's q: {sorted(q)}")
        out[name] = KeySpec(name, "m2 s-5", f"white-jerk intensity of the IMM's {mode} model").entry(q.pop())
    _put(
        out,
        runs,
        "nr.track.imm.manoeuvre_prob.mean",
        "1",
        "mean probability of the IMM's manoeuvre model",
        lambda rs: _stat(
            np.concatenate([r["mode_prob"].sel(mode="manoeuvre").values[r["t"].values >= SKIP_S] for r in rs]), np.mean
        ),
    )
    _put(
        out,
        runs,
        "nr.track.imm.manoeuvre_prob.after_change_mean",
        "1",
        f"mean probability of the IMM's manoeuvre model in the {w} after each acceleration change",
        lambda rs: _stat(_after(rs, "mode_prob", None, window_s), np.mean),
    )
    return out


def _put(out: dict[str, Any], runs: list[xr.Dataset], name, unit, desc, fn, lost_frac=None) -> None:
    """Enter the key ``name`` into ``out``: ``fn`` pooled over ``runs`` (:func:`_pooled`)."""
    value, se = _pooled(runs, fn)
    if lost_frac is not None:  # an accuracy: null where the track is lost too often
        value = loss.accuracy(value, lost_frac)
        se = se if value is not None else None
    out[name] = KeySpec(name, unit, desc).entry(value, se, lost_frac=lost_frac)


def _filter_keys(out: dict[str, Any], runs: list[xr.Dataset], f: str, window_s: float, spacing: float) -> None:
    """Enter the keys ``nr.track.{f}.*`` of filter ``f`` into ``out``: its lost share (track
    lost: 2-D error above half the RRH ``spacing`` [m]), errors, lag after the changes
    (``window_s``) and NEES."""
    w = f"{window_s:g} s"
    who = {
        "ekf": "the gated EKF (robust receiver, AOD+TOA; the source's eq. 10-14 with our gate)",
        "imm": "the IMM (same measurements and gate)",
        "rts": "the RTS-smoothed EKF (offline)",
    }[f]
    put = functools.partial(_put, out, runs)
    put(
        f"nr.track.{f}.lost_frac",
        "1",
        f"share of the scored epochs lost by {who} (2-D error above half the RRH spacing)",
        lambda rs, f=f: float(np.mean(loss.lost_mask(_overall(rs, "pos_err", f), spacing))),
    )
    lf = out[f"nr.track.{f}.lost_frac"]["value"]
    put(
        f"nr.track.{f}.tracked.err_m.mean",
        "m",
        f"mean 2-D position error of {who} over the epochs not lost",
        lambda rs, f=f: (lambda v: _stat(v[~loss.lost_mask(v, spacing)], np.mean))(_overall(rs, "pos_err", f)),
    )
    put(
        f"nr.track.{f}.err_m.mean",
        "m",
        f"mean 2-D position error of {who}",
        lambda rs, f=f: _stat(_overall(rs, "pos_err", f), np.mean),
        lf,
    )
    put(
        f"nr.track.{f}.err_m.p95",
        "m",
        f"95th percentile of the 2-D position error of {who}",
        lambda rs, f=f: _stat(_overall(rs, "pos_err", f), lambda v: np.percentile(v, 95)),
        lf,
    )
    put(
        f"nr.track.{f}.err_m.after_change_mean",
        "m",
        f"mean 2-D position error of {who} in the {w} after each acceleration change",
        lambda rs, f=f: _stat(_after(rs, "pos_err", f, window_s), np.mean),
        lf,
    )
    put(
        f"nr.track.{f}.lag_m.after_change_mean",
        "m",
        f"mean along-track lag −sign(Δa)·(x̂ − x) of {who} in the {w} after each acceleration change",
        lambda rs, f=f: _stat(_after(rs, "along_err", f, window_s, signed=True), np.mean),
        lf,
    )
    put(
        f"nr.track.{f}.nees.mean",
        "1",
        f"mean 2-D position NEES of {who} (2 for a consistent filter)",
        lambda rs, f=f: _stat(_overall(rs, "pos_nees", f), np.mean),
    )


def _running_mean(v: np.ndarray, n: int) -> np.ndarray:
    """Centered running mean over ``n`` samples (NaN-aware; shorter at the ends)."""
    ok = np.isfinite(v)
    k = np.ones(n)
    num = np.convolve(np.where(ok, v, 0.0), k, mode="same")
    den = np.convolve(ok.astype(float), k, mode="same")
    return np.where(den > 0, num / np.maximum(den, 1), np.nan)


def plot_lag(runs: list[xr.Dataset], pdf: str, png: str, window_s: float = 20.0, smooth_s: float = 1.0) -> None:
    """Error vs time around each acceleration change (±``window_s``), EKF vs IMM vs RTS,
    mean over the realizations and a centered ``smooth_s`` running mean; rows: 2-D error,
    signed along-track lag, IMM manoeuvre-model probability.

    Parameters
    ----------
    runs : list of xarray.Dataset
        The realizations' IMM datasets (:func:`railradio.nr.study.runs.track_imm`); the change epochs
        of the first are used.
    pdf : str
        Path of the PDF figure.
    png : str
        Path of the PNG copy.
    window_s : float
        Half-width of the window around each change, s (> 0).
    smooth_s : float
        Length of the running mean, s.

    Raises
    ------
    ValueError
        When ``window_s`` ≤ 0 (:func:`change_windows`).
    """
    wins = change_windows(runs[0], window_s, before_s=window_s)
    if not wins:
        fig, ax = plotting.figure(figsize=(6.4, 2.0))
        ax.text(0.5, 0.5, "no acceleration change within the run", ha="center", va="center", transform=ax.transAxes)
        ax.set_axis_off()
        plotting.save(fig, pdf, png)
        return
    dt = float(runs[0]["t"].values[1] - runs[0]["t"].values[0])
    n_s = max(int(round(smooth_s / dt)), 1)
    fig, axes = plotting.figure(
        nrows=3,
        ncols=len(wins),
        figsize=(2.4 * len(wins) + 0.6, 5.8),
        sharex=True,
        layout="constrained",
        sharey="row",
        squeeze=False,
    )
    for col, (c, idx, da) in enumerate(wins):
        rel = (idx - c) * dt
        for i, f in enumerate(FILTERS):
            err = np.nanmean([r["pos_err"].sel(filter=f).values[idx] for r in runs], axis=0)
            lag = np.nanmean([-np.sign(da) * r["along_err"].sel(filter=f).values[idx] for r in runs], axis=0)
            axes[0][col].plot(rel, _running_mean(err, n_s), color=f"C{i}", linewidth=0.8, label=LABEL[f])
            axes[1][col].plot(rel, _running_mean(lag, n_s), color=f"C{i}", linewidth=0.8)
        mu = np.nanmean([r["mode_prob"].sel(mode="manoeuvre").values[idx] for r in runs], axis=0)
        axes[2][col].plot(rel, mu, color="C1", linewidth=0.8)
        for row in range(3):
            axes[row][col].axvline(0.0, color="grey", linestyle=":", linewidth=0.8)
        axes[1][col].axhline(0.0, color="black", linewidth=0.5)
        axes[0][col].set_title(f"t = {float(runs[0]['t'].values[c]):.1f} s, Δa = {da:+.2f} m/s²", fontsize=7)
        axes[2][col].set_xlabel("time from the change [s]")
    axes[0][0].set_ylabel("2-D error [m]")
    axes[1][0].set_ylabel("lag −sign(Δa)(x̂−x) [m]")
    axes[2][0].set_ylabel("P(manoeuvre model)")
    axes[2][0].set_ylim(bottom=0.0)
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside upper center", ncol=3, fontsize=6)
    plotting.save(fig, pdf, png)
