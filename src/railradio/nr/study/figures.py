"""Figures of the nr study (source Fig. 3–5 and the error-vs-time view; the reproduction
map's and the conditions' claim grids: :mod:`railradio.nr.study.map_figures`)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from railradio import plotting
from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.study.keys import SPECS, toa_floor_m
from railradio.nr.waveform.numerology import SAMPLE_RATE_HZ

INTEGER_SAMPLE_FLOOR_M = SPEED_OF_LIGHT_M_S / SAMPLE_RATE_HZ / np.sqrt(12)
"""σ of a uniform ±c/(2F_s) range quantization error (0.35 m)."""

MEASUREMENTS_LABEL = {"aod": "AOD", "toa": "TOA", "aod_toa": "AOD+TOA"}


SOURCE_STYLE = {"marker": "x", "color": "black", "linestyle": "none", "markersize": 6, "zorder": 5}
"""How the source's published values are drawn on our curves."""


def _source_quantiles(prefix: str) -> list[tuple[float, float]]:
    """The source's quantile claims on a position-error CDF, (error m, CDF level), from the
    key-number specs (:data:`railradio.nr.study.keys.SPECS`: p95, p99 and the share below 1 m)."""
    pts = []
    for name, level in (("err_m.p95", 0.95), ("err_m.p99", 0.99)):
        if (v := SPECS.get(f"{prefix}.{name}", (None,) * 4)[2]) is not None:
            pts.append((float(v), level))
    if (v := SPECS.get(f"{prefix}.frac_submeter", (None,) * 4)[2]) is not None:
        pts.append((1.0, float(v)))
    return pts


def _cdf(ax, values, **kw):
    v = np.sort(np.asarray(values)[np.isfinite(values)])
    if v.size:
        ax.plot(v, np.arange(1, v.size + 1) / v.size, **kw)


def plot_trajectory(traj: xr.Dataset, pdf: str, png: str) -> None:
    """The train's trajectory: position [km] and speed [km/h] against time.

    Parameters
    ----------
    traj : xarray.Dataset
        ``t`` [s], ``x`` [m] and ``v`` [m/s] per epoch (the ``nr_trajectory`` rule's output).
    pdf : str
        Path of the PDF figure.
    png : str
        Path of the PNG copy.
    """
    fig, ax = plotting.figure()
    ax.plot(traj["t"], traj["x"] / 1e3, label="position")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("position x [km]")
    ax2 = ax.twinx()
    ax2.plot(traj["t"], traj["v"] * 3.6, color="C1", label="speed")
    ax2.set_ylabel("speed [km/h]")
    ax2.grid(False)
    fig.legend(loc="upper left", bbox_to_anchor=(0.12, 0.95))
    plotting.save(fig, pdf, png)


def plot_burst_correlation(samples: xr.Dataset, pdf: str, png: str) -> None:
    """|r̃_i[k]| of the nearest RRH for all SS blocks of one burst, side by side.

    Parameters
    ----------
    samples : xarray.Dataset
        A :func:`railradio.nr.engine.epochs.simulate_epochs` dataset with ``corr_sample`` (dims
        ``cand``, ``block``, ``lag``) and ``corr_sample_epoch``.
    pdf : str
        Path of the PDF figure.
    png : str
        Path of the PNG copy.
    """
    corr = samples["corr_sample"].isel(cand=0).values  # [block, lag]
    fig, ax = plotting.figure(figsize=(6.4, 3.0))
    n_b, n_k = corr.shape
    ax.plot(np.arange(n_b * n_k) / n_k, corr.ravel() / corr.max(), linewidth=0.5)
    ax.set_xlabel("SS block index (each block's correlation window)")
    ax.set_ylabel("normalized |r|")
    ax.set_title(f"epoch {int(samples['corr_sample_epoch'])}, nearest RRH", fontsize=8)
    plotting.save(fig, pdf, png)


def plot_measurement_cdf(tracks: list[xr.Dataset], pdf: str, png: str) -> None:
    """CDFs of the measured RRHs' |AOD error| [deg] and |TOA range error| [m], one curve per
    receiver, pooled over the realizations, with the half-sample range c/(2F_s) and the
    source's 95th percentiles (×) marked.

    Parameters
    ----------
    tracks : list of xarray.Dataset
        The realizations' track datasets (:func:`railradio.nr.study.runs.track_receivers`).
    pdf : str
        Path of the PDF figure.
    png : str
        Path of the PNG copy.
    """
    fig, (a1, a2) = plotting.figure(ncols=2, figsize=(6.8, 3.0))
    for i, rx in enumerate(tracks[0]["receiver"].values):
        aod = np.concatenate([np.abs(np.degrees(t["aod_err"].sel(receiver=rx).values.ravel())) for t in tracks])
        rng = np.concatenate([np.abs(t["range_err"].sel(receiver=rx).values.ravel()) for t in tracks])
        _cdf(a1, aod, label=str(rx), color=f"C{i}")
        _cdf(a2, rng, label=str(rx), color=f"C{i}")
    for ax, key in ((a1, "meas.aod_err_deg.p95"), (a2, "meas.toa_err_m.p95")):
        ax.plot([SPECS[key][2]], [0.95], label="source: 95th percentile", **SOURCE_STYLE)
    a1.set_xscale("log")
    a2.set_xscale("log")
    a1.set_xlabel("|AOD error| [deg]")
    a2.set_xlabel("|TOA range error| [m]")
    a1.set_ylabel("CDF")
    a2.axvline(SPEED_OF_LIGHT_M_S / SAMPLE_RATE_HZ / 2, **plotting.BOUND_STYLE, label="c/(2F_s)")
    a2.legend()
    plotting.save(fig, pdf, png)


def plot_position_cdf(
    tracks: list[xr.Dataset], pdf: str, png: str, skip_s: float = 5.0, bounds: list[xr.Dataset] | None = None
) -> None:
    """CDFs of the 2-D position error [m] after ``skip_s``, one panel per receiver: the EKF of
    each measurement set, the gated AOD+TOA EKF, the snapshot LS fix, the integer-sample σ and
    (with ``bounds``) the PCRB prediction; the source's quantile claims for its EKF (×: p95,
    p99, the share below 1 m).

    Parameters
    ----------
    tracks : list of xarray.Dataset
        The realizations' track datasets (:func:`railradio.nr.study.runs.track_receivers`).
    pdf : str
        Path of the PDF figure.
    png : str
        Path of the PNG copy.
    skip_s : float
        Errors before this time are left out, s.
    bounds : list of xarray.Dataset or None
        The realizations' bound datasets (``t`` [s], ``pcrb`` [m]), or ``None``.
    """
    rxs = tracks[0]["receiver"].values
    fig, axes = plotting.figure(ncols=len(rxs), figsize=(3.4 * len(rxs), 3.0), squeeze=False)
    for ax, rx in zip(axes[0], rxs, strict=True):
        for j, v in enumerate(tracks[0]["measurements"].values):
            e = np.concatenate(
                [t["pos_err"].sel(receiver=rx, measurements=v, gate=0).values[t["t"].values >= skip_s] for t in tracks]
            )
            _cdf(ax, e, label=f"EKF {MEASUREMENTS_LABEL[str(v)]}", color=f"C{j}")
        e = np.concatenate(
            [
                t["pos_err"].sel(receiver=rx, measurements="aod_toa", gate=1).values[t["t"].values >= skip_s]
                for t in tracks
            ]
        )
        _cdf(ax, e, label="EKF AOD+TOA, χ² gate", color="C2", linestyle="--")
        e = np.concatenate([t["snap_err"].sel(receiver=rx, measurements="aod_toa").values for t in tracks])
        _cdf(ax, e, label="snapshot LS", color="C3", linestyle=":")
        if bounds is not None:
            pc = np.concatenate([b["pcrb"].values[b["t"].values >= skip_s] for b in bounds])
            _cdf(ax, pc, label="PCRB prediction (measured error levels)", **plotting.BOUND_STYLE)
        ax.axvline(INTEGER_SAMPLE_FLOOR_M, color="grey", linestyle=":", linewidth=1.0, label="integer-sample σ")
        src = _source_quantiles("track.aod_toa")
        ax.plot(*zip(*src, strict=True), label="source: EKF AOD+TOA (p95, p99, share < 1 m)", **SOURCE_STYLE)
        ax.set_xscale("log")
        ax.set_xlim(1e-2, 1e4)  # diverged tracks leave the axis: their CDF stays below 1
        ax.set_xlabel("2-D position error [m]")
        ax.set_title(f"receiver: {rx}", fontsize=8)
    axes[0][0].set_ylabel("CDF")
    axes[0][0].legend(fontsize=6)
    plotting.save(fig, pdf, png)


def plot_error_vs_time(track: xr.Dataset, pdf: str, png: str, bounds: xr.Dataset | None = None) -> None:
    """2-D position error [m] against time of the AOD+TOA EKF (gate off and on) of every
    receiver, with the PCRB and snapshot PEB predictions when ``bounds`` is given.

    Parameters
    ----------
    track : xarray.Dataset
        One realization's track dataset (:func:`railradio.nr.study.runs.track_receivers`).
    pdf : str
        Path of the PDF figure.
    png : str
        Path of the PNG copy.
    bounds : xarray.Dataset or None
        The realization's bound dataset (``t`` [s]; ``pcrb``, ``peb``, optional
        ``pcrb_true_motion`` [m]), or ``None``.
    """
    fig, ax = plotting.figure(figsize=(6.4, 3.0))
    for i, rx in enumerate(track["receiver"].values):
        for g, style in ((0, "-"), (1, "--")):
            ax.plot(
                track["t"],
                track["pos_err"].sel(receiver=rx, measurements="aod_toa", gate=g),
                linewidth=0.6,
                linestyle=style,
                label=f"EKF AOD+TOA ({rx}{', gated' if g else ''})",
                color=f"C{2 * i + g}",
            )
    if bounds is not None:
        ax.plot(bounds["t"], bounds["pcrb"], label="PCRB prediction (white-jerk model)", **plotting.BOUND_STYLE)
        if "pcrb_true_motion" in bounds:
            ax.plot(
                bounds["t"],
                bounds["pcrb_true_motion"],
                color="black",
                linestyle=":",
                linewidth=1.0,
                label="PCRB prediction (true motion, genie)",
            )
        ax.plot(
            bounds["t"],
            bounds["peb"],
            color="grey",
            linewidth=0.6,
            label="snapshot PEB prediction (integer-sample TOA)",
        )
    ax.axhline(INTEGER_SAMPLE_FLOOR_M, color="grey", linestyle=":", linewidth=1.0, label="integer-sample σ (0.35 m)")
    ax.set_yscale("log")
    ax.set_ylim(1e-2, 1e8)  # headroom for the legend; diverged tracks leave the axis
    ax.set_xlabel("time [s]")
    ax.set_ylabel("2-D position error [m]")
    ax.legend(fontsize=6, loc="upper center", ncol=2)
    plotting.save(fig, pdf, png)


def plot_sensitivity(numbers: dict, cases: list[str], pdf: str, png: str) -> None:
    """Sensitivity cases beside the base run: TOA range error p95 and gated EKF mean error
    per receiver (key numbers ``sens.nr.<case>.<receiver>.*``); a tracker whose all-epoch
    accuracy is null because it loses the train is marked with its lost share.

    Parameters
    ----------
    numbers : dict
        Key numbers (name -> entry with ``value``), :func:`railradio.nr.study.keys.sensitivity_key_numbers`.
    cases : list of str
        The cases to show, in order (``"base"`` among them).
    pdf : str
        Path of the PDF figure.
    png : str
        Path of the PNG copy.
    """
    rxs = sorted(
        {k.split(".")[3] for k in numbers if k.startswith("sens.nr.")} - {"bound"}, key=lambda r: r != "source"
    )
    panels = (
        ("meas.toa_err_m.p95", "TOA range error p95 [m]"),
        ("track.aod_toa_gated.err_m.mean", "gated EKF AOD+TOA\nmean error [m]"),
    )
    fig, axes = plotting.figure(nrows=2, figsize=(7.2, 4.6), sharex=True)
    width = 0.8 / max(len(rxs), 1)
    x = np.arange(len(cases))
    for ax, (metric, label) in zip(axes, panels, strict=True):
        for i, rx in enumerate(rxs):
            vals = [numbers.get(f"sens.nr.{c}.{rx}.{metric}", {}).get("value") for c in cases]
            xs = x + (i - (len(rxs) - 1) / 2) * width
            ax.bar(xs, [np.nan if v is None else v for v in vals], width, color=f"C{i}", label=f"{rx} receiver")
            if metric.startswith("track."):
                for xi, c, v in zip(xs, cases, vals, strict=True):
                    lost = numbers.get(f"sens.nr.{c}.{rx}.track.aod_toa_gated.lost_frac", {}).get("value")
                    if v is None and lost is not None:
                        ax.text(
                            xi,
                            0.03,
                            f"lost {100 * lost:.0f} %",
                            transform=ax.get_xaxis_transform(),
                            rotation=90,
                            ha="center",
                            va="bottom",
                            fontsize=6,
                            color=f"C{i}",
                        )
        ax.set_yscale("log")
        ax.set_ylabel(label)
    axes[-1].set_xticks(x, cases, fontsize=7, rotation=35, ha="right")
    axes[0].legend(fontsize=7)
    plotting.save(fig, pdf, png)


def plot_sweeps(numbers: dict, sweeps: dict, sync_sigma_s: dict, pdf: str, png: str) -> None:
    """The nr sensitivity sweeps: one column per sweep; rows: median |TOA range error| with
    the integer-sample floor (widened by the RRH clock offsets where a case has them), the
    share of TOAs within 5 m (outliers: another RRH's peak or a false alarm) and the gated
    EKF AOD+TOA mean error, per receiver (key numbers ``sens.nr.<case>.<receiver>.*``); the
    sweep's reference point (the base settings) circled; a track lost in a case (no mean
    error: its ``lost_frac``) marked ▵ at the top of its panel.

    Parameters
    ----------
    numbers : dict
        Key numbers (name -> entry with ``value``), :func:`railradio.nr.study.keys.sensitivity_key_numbers`.
    sweeps : dict
        Sweep name -> ``{"cases": [case, ...], "reference": case}`` (the ``nr.sensitivity.sweeps``
        config).
    sync_sigma_s : dict of str to float
        Case name -> RRH clock spread σ, s (0 where absent).
    pdf : str
        Path of the PDF figure.
    png : str
        Path of the PNG copy.
    """
    rxs = sorted(
        {k.split(".")[3] for k in numbers if k.startswith("sens.nr.")} - {"bound"}, key=lambda r: r != "source"
    )
    rows = (
        ("meas.toa_err_m.median_abs", "median |TOA error| [m]", True),
        ("meas.toa_err_m.frac_lt_5m", "TOAs within 5 m", False),
        ("track.aod_toa_gated.err_m.mean", "gated EKF mean error [m]", True),
    )
    n = len(sweeps)
    lost_drawn = False
    fig, axes = plotting.figure(nrows=len(rows), ncols=n, figsize=(1.9 * n + 0.6, 6.0), squeeze=False, sharey="row")
    for j, (name, sw) in enumerate(sweeps.items()):
        x = np.arange(len(sw["cases"]))
        ref = sw.get("reference")
        for r, (metric, label, log) in enumerate(rows):
            ax = axes[r][j]
            for i, rx in enumerate(rxs):
                vals = np.array(
                    [
                        np.nan if (v := numbers.get(f"sens.nr.{c}.{rx}.{metric}", {}).get("value")) is None else v
                        for c in sw["cases"]
                    ]
                )
                ax.plot(x, vals, marker="o", color=f"C{i}", label=f"{rx} receiver")
                lost = [numbers.get(f"sens.nr.{c}.{rx}.{metric}", {}).get("lost_frac") or 0.0 for c in sw["cases"]]
                for xk, share, v in zip(x, lost, vals, strict=True):
                    if share > 0 and not np.isfinite(v):  # no error to plot: the track was lost
                        ax.plot(
                            xk,
                            0.96,
                            marker="^",
                            markerfacecolor="none",
                            color=f"C{i}",
                            linestyle="none",
                            transform=ax.get_xaxis_transform(),
                            label="track lost (no mean error)" if not lost_drawn else None,
                        )
                        lost_drawn = True
                if ref in sw["cases"]:
                    k = sw["cases"].index(ref)
                    ax.plot(x[k], vals[k], marker="o", markersize=9, markerfacecolor="none", color="black")
            if r == 0:
                floor = [toa_floor_m(sync_sigma_s.get(c, 0.0)) for c in sw["cases"]]
                ax.plot(x, floor, label="integer-sample floor", **plotting.BOUND_STYLE)
                ax.set_title(name.replace("_", " "), fontsize=8)
            if log:
                ax.set_yscale("log")
            else:
                ax.set_ylim(0, 1)
            ax.set_xticks(x, [str(v) for v in sw["values"]], fontsize=7)
            ax.tick_params(axis="y", labelsize=7)
            if r == len(rows) - 1:
                ax.set_xlabel(sw["label"], fontsize=7)
            if j == 0:
                ax.set_ylabel(label, fontsize=7)
    handles = {}
    for ax in axes.ravel():  # the lost marker may sit in another panel than the first
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(lab, h)
    axes[0][0].legend(list(handles.values()), list(handles), fontsize=6)
    plotting.save(fig, pdf, png)


def plot_fidelity(summary: dict, pdf: str, png: str) -> None:
    """Changed-decision shares of every shortcut (railradio.nr.study.fidelity), per receiver, with
    their 95 % intervals, the 0.5 % goal and a redraw of the noise as the yardstick.

    Parameters
    ----------
    summary : dict
        Comparison -> receiver -> decision -> ``{"frac", "lo", "hi"}`` (changed share and its 95 %
        interval, 1), :func:`railradio.nr.study.fidelity_stats.summarize`; must hold ``"noise"``.
    pdf : str
        Path of the PDF figure.
    png : str
        Path of the PNG copy.
    """
    from railradio.nr.study.fidelity import DECISIONS
    from railradio.nr.study.fidelity_stats import GOAL_CHANGE_FRAC

    comps = [c for c in summary if c != "noise"] + ["noise"]
    rxs = list(summary[comps[0]])
    fig, axes = plotting.figure(nrows=len(rxs), figsize=(6.8, 2.4 * len(rxs)), squeeze=False, sharex=True)
    floor = 1e-4
    width = 0.8 / len(DECISIONS)
    for ax, rx in zip(axes[:, 0], rxs, strict=True):
        for j, k in enumerate(DECISIONS):
            x = np.arange(len(comps)) + (j - (len(DECISIONS) - 1) / 2) * width
            m = [summary[c][rx][k] for c in comps]
            p = np.array([max(v["frac"], floor) for v in m])
            lo = np.array([max(v["lo"], floor) for v in m])
            hi = np.array([max(v["hi"], floor) for v in m])
            ax.bar(x, p, width=width, color=f"C{j}", label=k, bottom=0)
            ax.errorbar(x, p, yerr=[p - lo, hi - p], fmt="none", ecolor="black", elinewidth=0.6, capsize=1.5)
        ax.axhline(GOAL_CHANGE_FRAC, color="grey", linestyle="--", linewidth=0.8, label="0.5 % goal")
        ax.set_yscale("log")
        ax.set_ylim(floor, 1.0)
        ax.set_ylabel("changed share")
        ax.set_title(f"receiver: {rx}", fontsize=8)
    axes[-1, 0].set_xticks(np.arange(len(comps)))
    axes[-1, 0].set_xticklabels(comps, rotation=30, fontsize=7)
    axes[0, 0].legend(fontsize=6, ncol=5, loc="upper left")
    plotting.save(fig, pdf, png)
