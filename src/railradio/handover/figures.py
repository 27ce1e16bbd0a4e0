"""Figures of the handover study (source Fig. 4–8) and the sensitivity figure.

Rates carry 95 % Wilson intervals with the clustered effective sample size; means carry
±2 cluster-robust standard errors.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from railradio import plotting

LABELS = {
    "joint": "joint decision (ours, reconstructed)",
    "a3": "A3 event",
    "a3_rail": "A3, railway-tuned",
    "distance": "distance trigger",
}
MARKERS = {"joint": "o", "a3": "s", "a3_rail": "D", "distance": "^"}
DELAY_REQUIREMENT_MS = 45.0
"""Handover delay requirement of the Chinese railway radio standard quoted by the source."""
SUCCESS_REQUIREMENT = 0.995
"""Success-rate requirement quoted by the source (interruption ≤ 0.5 %); the railway
requirement of ETSI as quoted by Cho et al., IEEE Commun. Mag. 54(10), 2016 (LTE-R handover
point control): a handover success rate of at least 0.995."""
SOURCE_BEST_M = 3


def plot_cost_vs_m(cost: xr.Dataset, pdf_path, png_path=None) -> None:
    """Minimum cost over α per m for both WSLR readings (source Fig. 4).

    Parameters
    ----------
    cost : xarray.Dataset
        A cost dataset of :func:`railradio.handover.cost.cost_grid`: ``cost`` J and its standard
        error ``cost_se`` [1] over (``wslr``, ``m``, ``alpha``), the scalars ``speed_kmh``
        [km/h] and ``n_runs``; when present, ``cost_min_full_grid`` [1] (m), ``within_1se`` and
        the attribute ``config_wslr``.
    pdf_path : str or os.PathLike
        Path of the PDF to write.
    png_path : str or os.PathLike or None, optional
        Path of the PNG to write (default: ``pdf_path`` with the suffix ``.png``).
    """
    fig, ax = plotting.figure()
    m = cost["m"].values
    for meth, marker in zip(cost["wslr"].values, ("o", "s"), strict=False):
        c = cost["cost"].sel(wslr=meth)
        ia = c.argmin("alpha")
        y = c.min("alpha").values
        se = cost["cost_se"].sel(wslr=meth).isel(alpha=ia).values
        ax.errorbar(m, y, yerr=2 * se, marker=marker, capsize=2, markerfacecolor="none", label=f"WSLR as {meth}")
    if "cost_min_full_grid" in cost and np.any(np.isfinite(cost["cost_min_full_grid"].values)):
        ax.plot(
            m,
            cost["cost_min_full_grid"].values,
            "x",
            color="black",
            label=f"full weight grid ({cost.attrs.get('config_wslr', '')})",
        )
    cfg = cost.attrs.get("config_wslr", "")
    if "within_1se" in cost and cfg in cost["wslr"].values:
        c = cost["cost"].sel(wslr=cfg)
        flat = int(c.values.argmin())
        se = float(cost["cost_se"].sel(wslr=cfg).values.ravel()[flat])
        ax.axhline(
            float(c.min()) + se,
            color="grey",
            linestyle=":",
            linewidth=1,
            label=f"minimum + 1 SE ({cfg}): settings below are not separable",
        )
    ax.axvline(SOURCE_BEST_M, **plotting.BOUND_STYLE, label=f"source: m = {SOURCE_BEST_M}")
    ax.set_xlabel("number of joint nodes $m$")
    ax.set_ylabel(r"min$_\alpha$ cost $J = E[C/N] + E[F]$")
    ax.set_title(f"{float(cost['speed_kmh']):g} km/h, {int(cost['n_runs'])} crossings", fontsize="small")
    ax.legend()
    plotting.save(fig, pdf_path, png_path)


def _rate_plot(ax, summary, name, transform=None, log=False):
    v = summary["speed_kmh"].values
    dv = 0.006 * (v.max() - v.min() + 1.0)  # side-by-side offsets of the upper-bound markers
    bounds = False
    for j, pol in enumerate(summary["policy"].values):
        p = summary[name].sel(policy=pol).values
        lo = summary[f"{name}_lo"].sel(policy=pol).values
        hi = summary[f"{name}_hi"].sel(policy=pol).values
        if transform is not None:
            p, lo, hi = transform(p), transform(hi), transform(lo)
        err = np.maximum(np.vstack([p - lo, hi - p]), 0.0)
        shown = p > 0 if log else np.ones_like(p, dtype=bool)
        cont = ax.errorbar(
            v[shown],
            p[shown],
            yerr=err[:, shown],
            marker=MARKERS.get(str(pol), "o"),
            capsize=2,
            markerfacecolor="none",
            label=LABELS.get(str(pol), str(pol)),
        )
        if log and np.any(~shown):  # zero observed: draw the upper bound only
            ax.plot(v[~shown] + (j - 1) * dv, hi[~shown], marker="v", linestyle="none", color=cont[0].get_color())
            bounds = True
    if log and bounds:  # one legend entry for every policy's markers
        ax.plot([], [], marker="v", linestyle="none", color="grey", label="none observed: 95 % upper bound")


def _decades(ax) -> None:
    """Log y ticks at the decades only, labelled 10ⁿ (one format from 10⁻⁶ to 1)."""
    from matplotlib.ticker import LogFormatterSciNotation, LogLocator, NullFormatter

    ax.yaxis.set_major_locator(LogLocator(base=10))
    ax.yaxis.set_major_formatter(LogFormatterSciNotation(base=10))
    ax.yaxis.set_minor_locator(LogLocator(base=10, subs=np.arange(2, 10)))
    ax.yaxis.set_minor_formatter(NullFormatter())


def plot_pingpong_vs_speed(summary: xr.Dataset, pdf_path, png_path=None) -> None:
    """Ping-pong rate against speed (source Fig. 5); ▽ = upper 95 % bound where none was seen.

    Parameters
    ----------
    summary : xarray.Dataset
        Rates and means per policy and speed (:func:`railradio.handover.summary.metrics_dataset`
        over (``policy``, ``speed_kmh``), speeds in km/h): the ping-pong rate ``pingpong``
        [1] and its 95 % interval ``pingpong_lo``, ``pingpong_hi`` [1].
    pdf_path : str or os.PathLike
        Path of the PDF to write.
    png_path : str or os.PathLike or None, optional
        Path of the PNG to write (default: ``pdf_path`` with the suffix ``.png``).
    """
    fig, ax = plotting.figure()
    _rate_plot(ax, summary, "pingpong", log=True)
    plotting.log_axis(ax, "y")
    _decades(ax)
    ax.set_xlabel("train speed [km/h]")
    ax.set_ylabel("ping-pong rate")
    ax.legend()
    plotting.save(fig, pdf_path, png_path)


def plot_interruption_vs_speed(summary: xr.Dataset, pdf_path, png_path=None) -> None:
    """Interruption rate 1 − success against speed with the 99.5 % success line (source Fig. 8).

    Parameters
    ----------
    summary : xarray.Dataset
        Rates and means per policy and speed (:func:`railradio.handover.summary.metrics_dataset`
        over (``policy``, ``speed_kmh``), speeds in km/h): the success rate ``success`` [1]
        and its 95 % interval ``success_lo``, ``success_hi`` [1], drawn as 1 − success.
    pdf_path : str or os.PathLike
        Path of the PDF to write.
    png_path : str or os.PathLike or None, optional
        Path of the PNG to write (default: ``pdf_path`` with the suffix ``.png``).
    """
    fig, ax = plotting.figure()
    _rate_plot(ax, summary, "success", transform=lambda p: 1.0 - p, log=True)
    ax.axhline(1 - SUCCESS_REQUIREMENT, **plotting.BOUND_STYLE, label="requirement: success ≥ 99.5 %")
    plotting.log_axis(ax, "y")
    _decades(ax)
    ax.set_xlabel("train speed [km/h]")
    ax.set_ylabel("interruption rate (1 − success)")
    ax.legend()
    plotting.save(fig, pdf_path, png_path)


def plot_stages_vs_speed(summary: xr.Dataset, pdf_path, png_path=None) -> None:
    """The failure stages against speed (``execution.failure_rule: stages``): interruption
    rate 1 − success with the 99.5 % requirement, the too-late and too-early shares, and the
    interruption time's median and 95th percentile.

    Parameters
    ----------
    summary : xarray.Dataset
        Rates and means per policy and speed (:func:`railradio.handover.summary.metrics_dataset`):
        ``success``, ``too_late``, ``too_early`` [1] with their 95 % intervals (``_lo``,
        ``_hi``), ``interruption_ms_median`` and ``interruption_ms_p95`` [ms].
    pdf_path : str or os.PathLike
        Path of the PDF to write.
    png_path : str or os.PathLike or None, optional
        Path of the PNG to write (default: ``pdf_path`` with the suffix ``.png``).
    """
    fig, axes = plotting.figure(nrows=2, ncols=2, figsize=(9.0, 6.6), sharex=True)
    ax = axes[0, 0]
    _rate_plot(ax, summary, "success", transform=lambda p: 1.0 - p, log=True)
    ax.axhline(1 - SUCCESS_REQUIREMENT, **plotting.BOUND_STYLE, label="requirement: success ≥ 99.5 %")
    plotting.log_axis(ax, "y")
    _decades(ax)
    ax.set_ylabel("failed handovers (1 − success)")
    ax.set_title("every stage", fontsize="small")
    ax.legend(fontsize="x-small")
    for ax, name, ylabel in (
        (axes[0, 1], "too_late", "too late (serving side failed)"),
        (axes[1, 0], "too_early", "too early (access or new link failed)"),
    ):
        if np.all(np.isnan(summary[name].values)):
            ax.set_axis_off()
            continue
        _rate_plot(ax, summary, name, log=True)
        pairs = zip(*ax.get_legend_handles_labels(), strict=True)
        handles = [(h, t) for h, t in pairs if t.startswith("none observed")]
        if handles:  # the ▼ markers explained where they are drawn (the policies: the first panel)
            ax.legend(*zip(*handles, strict=True), fontsize="x-small", loc="best")
        plotting.log_axis(ax, "y")
        _decades(ax)
        ax.set_ylabel("share of handovers")
        ax.set_title(ylabel, fontsize="small")
    ax = axes[1, 1]
    v = summary["speed_kmh"].values
    for pol in summary["policy"].values:
        line = ax.plot(
            v,
            summary["interruption_ms_median"].sel(policy=pol).values,
            marker=MARKERS.get(str(pol), "o"),
            markerfacecolor="none",
            label=LABELS.get(str(pol), str(pol)),
        )
        ax.plot(
            v,
            summary["interruption_ms_p95"].sel(policy=pol).values,
            marker=MARKERS.get(str(pol), "o"),
            linestyle="--",
            color=line[0].get_color(),
        )
    ax.plot([], [], color="grey", label="median")
    ax.plot([], [], color="grey", linestyle="--", label="95th percentile")
    plotting.log_axis(ax, "y")
    ax.set_ylim(20.0, 400.0)
    ax.set_ylabel("interruption [ms]")
    ax.set_title("command to completion, re-establishment included", fontsize="small")
    ax.legend(fontsize="x-small")
    for ax in axes[1]:
        ax.set_xlabel("train speed [km/h]")
    plotting.save(fig, pdf_path, png_path)


def _mean_plot(summary, name, ylabel, pdf_path, png_path, hline=None, hlabel=None):
    fig, ax = plotting.figure()
    v = summary["speed_kmh"].values
    for pol in summary["policy"].values:
        y = summary[name].sel(policy=pol).values
        se = summary[f"{name}_se"].sel(policy=pol).values
        ax.errorbar(
            v,
            y,
            yerr=2 * se,
            marker=MARKERS.get(str(pol), "o"),
            capsize=2,
            markerfacecolor="none",
            label=LABELS.get(str(pol), str(pol)),
        )
    if hline is not None:
        ax.axhline(hline, **plotting.BOUND_STYLE, label=hlabel)
    ax.set_xlabel("train speed [km/h]")
    ax.set_ylabel(ylabel)
    ax.legend()
    plotting.save(fig, pdf_path, png_path)


def plot_delay_vs_speed(summary: xr.Dataset, pdf_path, png_path=None) -> None:
    """Mean handover delay against speed with the 45 ms requirement (source Fig. 7): command to
    completion over all handovers (successful only, the source's reading, dotted) and trigger to
    completion.

    Parameters
    ----------
    summary : xarray.Dataset
        Rates and means per policy and speed (:func:`railradio.handover.summary.metrics_dataset`
        over (``policy``, ``speed_kmh``), speeds in km/h): the mean delays ``delay_all_ms``,
        ``delay_trigger_ms`` and, when present, ``delay_ms`` [ms], each with its standard error
        ``_se`` [ms] (error bars ±2 standard errors).
    pdf_path : str or os.PathLike
        Path of the PDF to write.
    png_path : str or os.PathLike or None, optional
        Path of the PNG to write (default: ``pdf_path`` with the suffix ``.png``).
    """
    fig, axes = plotting.figure(ncols=2, figsize=(9.0, 3.4))
    v = summary["speed_kmh"].values
    panels = (
        (axes[0], (("delay_all_ms", "-"), ("delay_ms", ":")), "command to completion [ms]"),
        (axes[1], (("delay_trigger_ms", "-"),), "trigger to completion [ms]"),
    )
    for ax, names, ylabel in panels:
        for pol in summary["policy"].values:
            color = None
            for name, ls in names:
                if name not in summary:
                    continue
                y = summary[name].sel(policy=pol).values
                se = summary[f"{name}_se"].sel(policy=pol).values
                label = LABELS.get(str(pol), str(pol)) + (" (successful only)" if name == "delay_ms" else "")
                cont = ax.errorbar(
                    v,
                    y,
                    yerr=2 * se,
                    marker=MARKERS.get(str(pol), "o"),
                    capsize=2,
                    markerfacecolor="none",
                    linestyle=ls,
                    color=color,
                    label=label,
                )
                color = cont[0].get_color()
        ax.axhline(DELAY_REQUIREMENT_MS, **plotting.BOUND_STYLE, label="requirement: 45 ms")
        ax.set_xlabel("train speed [km/h]")
        ax.set_ylabel(ylabel)
    axes[0].legend(fontsize="x-small")
    plotting.save(fig, pdf_path, png_path)


def plot_rsrp_gap_vs_speed(summary: xr.Dataset, pdf_path, png_path=None) -> None:
    """Mean |RSRP-GAP| at completion against speed (source Fig. 6).

    Parameters
    ----------
    summary : xarray.Dataset
        Rates and means per policy and speed (:func:`railradio.handover.summary.metrics_dataset`
        over (``policy``, ``speed_kmh``), speeds in km/h): the mean absolute gap
        ``rsrp_gap_db`` [dB] and its standard error ``rsrp_gap_db_se`` [dB].
    pdf_path : str or os.PathLike
        Path of the PDF to write.
    png_path : str or os.PathLike or None, optional
        Path of the PNG to write (default: ``pdf_path`` with the suffix ``.png``).
    """
    _mean_plot(summary, "rsrp_gap_db", "mean |RSRP-GAP| at completion [dB]", pdf_path, png_path)


def plot_sensitivity(sens: xr.Dataset, pdf_path, png_path=None) -> None:
    """Interruption and ping-pong rate of every sensitivity case (95 % intervals).

    Parameters
    ----------
    sens : xarray.Dataset
        Rates per policy and sensitivity ``case``: ``success`` and ``pingpong`` [1] with their
        95 % intervals ``_lo``, ``_hi`` [1], ``affected`` (``case``, ``policy``; only a
        policy the case can change is drawn) and the scalar ``speed_kmh`` [km/h].
    pdf_path : str or os.PathLike
        Path of the PDF to write.
    png_path : str or os.PathLike or None, optional
        Path of the PNG to write (default: ``pdf_path`` with the suffix ``.png``).
    """
    cases = [str(v) for v in sens["case"].values]
    fig, axes = plotting.figure(ncols=2, figsize=(9.0, 0.28 * len(cases) + 1.6), sharey=True)
    y = np.arange(len(cases))
    for j, pol in enumerate(sens["policy"].values):
        aff = sens["affected"].sel(policy=pol).values.astype(bool)
        dy = (j - 1) * 0.22
        for ax, name, tr in ((axes[0], "success", lambda p: 1 - p), (axes[1], "pingpong", None)):
            p = sens[name].sel(policy=pol).values
            lo = sens[f"{name}_lo"].sel(policy=pol).values
            hi = sens[f"{name}_hi"].sel(policy=pol).values
            if tr is not None:
                p, lo, hi = tr(p), tr(hi), tr(lo)
            ax.errorbar(
                p[aff],
                y[aff] + dy,
                xerr=np.maximum(np.vstack([p - lo, hi - p]), 0.0)[:, aff],
                linestyle="none",
                marker=MARKERS.get(str(pol), "o"),
                markerfacecolor="none",
                capsize=2,
                label=LABELS.get(str(pol), str(pol)),
            )
    axes[0].set_yticks(y, [v if v != "reference" else "reference" for v in cases], fontsize="small")
    axes[0].invert_yaxis()
    axes[0].set_xlabel("interruption rate (1 − success)")
    axes[1].set_xlabel("ping-pong rate")
    axes[0].axvline(1 - SUCCESS_REQUIREMENT, **plotting.BOUND_STYLE)
    axes[0].legend(fontsize="x-small")
    axes[0].set_title(f"{float(sens['speed_kmh']):g} km/h", fontsize="small")
    plotting.save(fig, pdf_path, png_path)


FIGURES = {
    "handover_cost_vs_m": ("cost", plot_cost_vs_m),
    "handover_pingpong_vs_speed": ("summary", plot_pingpong_vs_speed),
    "handover_rsrp_gap_vs_speed": ("summary", plot_rsrp_gap_vs_speed),
    "handover_delay_vs_speed": ("summary", plot_delay_vs_speed),
    "handover_interruption_vs_speed": ("summary", plot_interruption_vs_speed),
    "handover_stages_vs_speed": ("summary", plot_stages_vs_speed),
    "handover_sensitivity": ("sensitivity", plot_sensitivity),
}
"""Figure name -> (input dataset, plotting function).

The input is ``cost`` (:func:`railradio.handover.cost.cost_grid`), ``summary`` (rates and
means per policy and speed) or ``sensitivity`` (per policy and case); every plotting
function takes ``(dataset, pdf_path, png_path=None)`` and writes the figure.
"""
