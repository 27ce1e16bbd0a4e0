"""q as a band (docs/model/nr.md §6): the process-noise intensities the calibration can not
tell apart, and the headline tracker's accuracy over them.

The calibration picks the q whose position NEES on the calibration run is most consistent,
cost(q) = |log(median NEES / median χ²₂)| (:func:`railradio.nr.tracking.calibration.calibrate`).
That cost is itself an estimate from one run. The rule, fixed before the run [ours]: q is
**in the band** when the 95 % interval of cost(q) − cost(q̂) under a paired moving-block
bootstrap of the calibration run's epochs contains 0 — blocks of :data:`BLOCK_S` seconds, longer
than the tracker's error correlation, resampled alike for every q, :data:`N_BOOT` resamples from
the configuration seed. The headline tracker is then run on every realization at every q
tried, and its accuracy over the band is reported as a band (its least and largest value),
beside the value at the calibrated q̂.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr
from scipy.stats import chi2

from railradio.keynumbers import KeySpec
from railradio.nr.engine.simulate import Scenario
from railradio.nr.study.keys import SKIP_S
from railradio.nr.study.runs import tracker_name
from railradio.nr.tracking import loss
from railradio.nr.tracking.ekf import TrackerConfig, nees_position
from railradio.nr.tracking.track import track
from railradio.plotting import figure, save

BLOCK_S = 10.0
"""Bootstrap block length [s] [ours]: 100 epochs, several times the EKF's settling after a
disturbance, so blocks are close to independent."""
N_BOOT = 1000
"""Bootstrap resamples [ours]."""
LEVEL = 0.95
"""Two-sided level of the interval of cost(q) - cost(q̂) [ours]."""
Q_BAND_ID = 3000
"""Spawn-key sub-ID of the bootstrap's generator (``spawn_key("nr", Q_BAND_ID)``)."""
RECEIVER, MEASUREMENTS, GATE = "robust", "aod_toa", True
"""The headline tracker: our receiver, AOD+TOA, with the χ² gate."""


def track_run(ds: xr.Dataset, scn: Scenario, cfg: TrackerConfig, strength: str) -> dict[str, np.ndarray]:
    """One receiver's estimates tracked on the scenario's deployment, as the main run tracks
    them (:func:`railradio.nr.tracking.track.track`, no snapshot baseline).

    Parameters
    ----------
    ds : xarray.Dataset
        One receiver's estimates (a realization's, selected at one ``receiver``).
    scn : Scenario
        The scenario (deployment, ``trajectory.dt_s``).
    cfg : TrackerConfig
        The tracker settings.
    strength : str
        The receiver's strength measure of its measured RRHs.

    Returns
    -------
    dict
        :func:`railradio.nr.tracking.track.track`'s output (``state`` [epoch, 6], ``cov``, ...).
    """
    dep = scn.deployment
    return track(
        ds, dep.x_m, dep.offset_m, dep.h_bs_m - dep.h_ut_m, scn.trajectory.dt_s, cfg, strength=strength, snapshot=False
    )


def _nan_stat(v: np.ndarray, fn) -> float:
    return float(fn(v)) if np.isfinite(v).any() else np.nan


def band(
    nees: np.ndarray, i_hat: int, block: int, n_boot: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which q the calibration can not tell from q̂ (module docstring).

    Parameters
    ----------
    nees : numpy.ndarray
        Position NEES [q, epoch] of the calibration run's tracks at each q [1] (NaN where a
        track has not started).
    i_hat : int
        Index of the calibrated q̂.
    block : int
        Block length [epochs], >= 1.
    n_boot : int
        Resamples, >= 1.
    rng : numpy.random.Generator
        Source of the resampled block starts.

    Returns
    -------
    tuple of numpy.ndarray
        ``(in_band, lo, hi)``, each [q]: in the band (bool; q̂ always is), and the interval of
        cost(q) - cost(q̂) at :data:`LEVEL` [1].

    Raises
    ------
    ValueError
        When ``block`` or ``n_boot`` is below 1 or the run is shorter than one block.
    """
    n_q, n = nees.shape
    if block < 1 or n_boot < 1:
        raise ValueError(f"block and n_boot must be >= 1, got {block!r}, {n_boot!r}")
    if n < block:
        raise ValueError(f"the run ({n} epochs) is shorter than one block ({block})")
    n_blocks = int(np.ceil(n / block))
    starts = rng.integers(0, n - block + 1, size=(n_boot, n_blocks))
    med = np.empty((n_q, n_boot))
    for a in range(0, n_boot, 50):  # 50 resamples at a time: [q, 50, n] in memory
        idx = (starts[a : a + 50, :, None] + np.arange(block)).reshape(starts[a : a + 50].shape[0], -1)[:, :n]
        med[:, a : a + 50] = np.nanmedian(nees[:, idx], axis=2)
    cost = np.abs(np.log(med / chi2.median(2)))
    diff = cost - cost[i_hat]
    lo, hi = np.nanquantile(diff, [(1 - LEVEL) / 2, (1 + LEVEL) / 2], axis=1)
    out = (lo <= 0.0) & (hi >= 0.0)
    out[i_hat] = True
    return out, lo, hi


def q_band(
    cal_ds: xr.Dataset,
    runs: Sequence[xr.Dataset],
    scn: Scenario,
    cal: dict[str, dict],
    tracker: dict[str, Any],
    selection: dict[str, str],
    rng: np.random.Generator,
    spacing_m: float,
) -> xr.Dataset:
    """The headline tracker at every q its calibration tried: the calibration cost, whether
    q is in the band, and the accuracy pooled over the realizations.

    Parameters
    ----------
    cal_ds : xarray.Dataset
        The calibration run's estimates (all receivers; :func:`railradio.nr.study.runs.read_shards`
        and :func:`~railradio.nr.study.runs.point_model`).
    runs : sequence of xarray.Dataset
        Each evaluation realization's estimates, prepared alike.
    scn : Scenario
        The scenario (deployment, ``trajectory.dt_s``).
    cal : dict of str to dict
        The calibration records (``results/nr/calibration.json``); the headline tracker's
        ``q_search`` gives the q values.
    tracker : dict
        The ``nr.tracker`` config section (``gate_prob``).
    selection : dict of str to str
        Receiver name -> strength measure of its measured RRHs.
    rng : numpy.random.Generator
        Bootstrap generator.
    spacing_m : float
        RRH spacing [m], the loss rule's threshold (:func:`railradio.nr.tracking.loss.lost_mask`).

    Returns
    -------
    xarray.Dataset
        Over ``q`` [m² s⁻⁵]: ``cost`` (calibration NEES cost) [1], ``in_band`` [bool],
        ``diff_lo``, ``diff_hi`` (the bootstrap interval of cost - cost(q̂)) [1],
        ``err_mean_m``, ``err_p95_m`` (2-D error after the first ``SKIP_S`` seconds, pooled over
        the realizations, as the headline keys count it) [m], ``lost_frac`` [1] (the loss
        rule's share; the keys null an accuracy above 1 %). Attributes
        ``q_hat`` [m² s⁻⁵], ``block_s`` [s], ``n_boot``, ``level``. ``in_band`` is stored as 0/1.

    Raises
    ------
    KeyError
        When the calibration lacks the headline tracker.
    """
    rec = cal[tracker_name(RECEIVER, MEASUREMENTS, GATE)]
    qs = np.asarray(rec["q_search"]["q"], dtype=float)
    base = TrackerConfig.from_record(rec, measurements=MEASUREMENTS, gate=GATE, gate_prob=tracker["gate_prob"])
    strength = selection[RECEIVER]
    dsc = cal_ds.sel(receiver=RECEIVER)
    nees = np.empty((qs.size, dsc.sizes["epoch"]))
    for i, q in enumerate(qs):
        o = track_run(dsc, scn, dataclasses.replace(base, q=float(q)), strength)
        nees[i] = nees_position(o["state"], o["cov"], dsc["x_true"].values)  # scoring the survey run
    i_hat = int(np.argmin(np.abs(np.log(qs / float(rec["q"])))))
    block = max(1, int(round(BLOCK_S / scn.trajectory.dt_s)))
    in_band, lo, hi = band(nees, i_hat, block, N_BOOT, rng)
    cost = np.abs(np.log(np.nanmedian(np.where(np.isfinite(nees), nees, np.nan), axis=1) / chi2.median(2)))
    stats = np.full((3, qs.size), np.nan)
    for i, q in enumerate(qs):
        cfg = dataclasses.replace(base, q=float(q))
        errs = []
        for ds in runs:
            d = ds.sel(receiver=RECEIVER)
            o = track_run(d, scn, cfg, strength)
            keep = d["t"].values >= SKIP_S
            errs.append(np.hypot(o["state"][:, 0] - d["x_true"].values, o["state"][:, 1])[keep])
        err = np.concatenate(errs)
        # the headline keys' statistics: every scored epoch, null by the loss rule when lost
        lost = np.mean(loss.lost_mask(err, spacing_m))
        stats[:, i] = lost, _nan_stat(err, np.nanmean), _nan_stat(err, lambda v: np.nanpercentile(v, 95))
    return xr.Dataset(
        {
            "cost": (
                "q",
                cost,
                {"units": "1", "long_name": "calibration NEES cost |log(median NEES / median chi2_2)|"},
            ),
            "in_band": (
                "q",
                in_band.astype(np.int8),
                {"units": "1", "long_name": "1: the calibration can not tell q from q_hat (paired block bootstrap)"},
            ),
            "diff_lo": (
                "q",
                lo,
                {"units": "1", "long_name": f"{LEVEL:.0%} bootstrap interval of cost - cost(q_hat): low"},
            ),
            "diff_hi": (
                "q",
                hi,
                {"units": "1", "long_name": f"{LEVEL:.0%} bootstrap interval of cost - cost(q_hat): high"},
            ),
            "lost_frac": ("q", stats[0], {"units": "1", "long_name": "share of epochs lost"}),
            "err_mean_m": ("q", stats[1], {"units": "m", "long_name": "mean 2-D error after SKIP_S"}),
            "err_p95_m": ("q", stats[2], {"units": "m", "long_name": "95th pct 2-D error after SKIP_S"}),
        },
        coords={"q": ("q", qs, {"units": "m2 s-5", "long_name": "white-jerk intensity"})},
        attrs={"q_hat": float(rec["q"]), "block_s": BLOCK_S, "n_boot": N_BOOT, "level": LEVEL},
    )


def key_numbers(qb: xr.Dataset) -> dict[str, Any]:
    """Key numbers ``nr.qband.*`` of :func:`q_band`'s dataset.

    Parameters
    ----------
    qb : xarray.Dataset
        :func:`q_band`'s output.

    Returns
    -------
    dict
        Key-number entries (:meth:`railradio.keynumbers.KeySpec.entry`).
    """
    sel = qb.sel(q=qb["q"].values[qb["in_band"].values.astype(bool)])
    at = qb.sel(q=qb.attrs["q_hat"])
    lost = float(sel["lost_frac"].max())
    out: dict[str, Any] = {}

    def put(name, unit, desc, value, lost_frac=None, digits=3):
        v = None if value is None or not np.isfinite(value) else float(value)
        if lost_frac is not None:
            v = loss.accuracy(v, lost_frac)
        out[f"nr.qband.{name}"] = KeySpec(f"nr.qband.{name}", unit, desc, digits=digits).entry(v, lost_frac=lost_frac)

    tr = "the headline tracker (our receiver, AOD+TOA, chi2 gate)"
    put("q_hat", "m^2 s^-5", "q the calibration chose for " + tr, qb.attrs["q_hat"])
    put("n_q", "1", "q values the calibration tried", qb.sizes["q"], digits=2)
    put(
        "n_in_band",
        "1",
        "q values the calibration can not tell from q_hat (paired block bootstrap, 95 %)",
        int(sel.sizes["q"]),
        digits=2,
    )
    put("q_lo", "m^2 s^-5", "smallest q in the band", float(sel["q"].min()))
    put("q_hi", "m^2 s^-5", "largest q in the band", float(sel["q"].max()))
    for stat, what in (("mean", "mean"), ("p95", "95th pct")):
        v = sel[f"err_{stat}_m"].values
        put(f"err_m.{stat}.lo", "m", f"least {what} 2-D error of {tr} over the q band", np.nanmin(v), lost)
        put(f"err_m.{stat}.hi", "m", f"largest {what} 2-D error of {tr} over the q band", np.nanmax(v), lost)
        put(
            f"err_m.{stat}.at_q_hat",
            "m",
            f"{what} 2-D error of {tr} at q_hat (the headline)",
            float(at[f"err_{stat}_m"]),
            float(at["lost_frac"]),
        )
    put("lost_frac.max", "1", "largest share of epochs lost over the q band", lost)
    return out


def plot_band(qb: xr.Dataset, pdf, png) -> None:
    """Figure ``nr_q_band``: the calibration's NEES cost against q and, at each q, cost(q̂)
    plus the bootstrap interval of cost(q) - cost(q̂) (top; in the band when the interval holds
    0, i.e. the bar meets cost(q̂), dotted),
    and the headline tracker's mean and 95th-percentile error against q (bottom), the band
    shaded and q̂ marked.

    Parameters
    ----------
    qb : xarray.Dataset
        :func:`q_band`'s output.
    pdf, png : str or os.PathLike
        Output paths.

    Returns
    -------
    None
        The figure is written to ``pdf`` and ``png``.
    """
    q = qb["q"].values
    inb = qb["in_band"].values.astype(bool)
    q_hat = qb.attrs["q_hat"]
    c_hat = float(qb["cost"].sel(q=q_hat))
    fig, (ac, ae) = figure(nrows=2, figsize=(6.0, 5.6), sharex=True, layout="constrained")
    ac.plot(q, qb["cost"], "o-", label="calibration NEES cost |log(median NEES / median χ²₂)|")
    level = f"{qb.attrs['level']:.0%}"
    ac.vlines(
        q,
        c_hat + qb["diff_lo"],
        c_hat + qb["diff_hi"],
        color="grey",
        lw=2,
        alpha=0.6,
        label=f"cost(q̂) + the {level} bootstrap interval of cost(q) - cost(q̂): in the band if it meets the dots",
    )
    ac.axhline(c_hat, color="k", ls=":", lw=0.8)
    ae.plot(q, qb["err_mean_m"], "o-", label="mean")
    ae.plot(q, qb["err_p95_m"], "s-", label="95th percentile")
    for a in (ac, ae):
        a.set_xscale("log")
        if inb.any():
            a.axvspan(q[inb].min(), q[inb].max(), color="tab:green", alpha=0.08, lw=0)
        a.axvline(q_hat, color="k", ls="--", lw=0.8)
    ac.set_ylabel("cost [1]")
    ac.legend(fontsize=7)
    ae.set_xlabel("white-jerk intensity q [m² s⁻⁵] (shaded: the band; dashed: calibrated q̂)")
    ae.set_ylabel("2-D position error [m]")
    ae.legend(fontsize=7)
    save(fig, pdf, png)
