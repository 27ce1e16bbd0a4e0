"""Figure ``chain_success_vs_sigma``: handover success vs the position error σ."""

from __future__ import annotations

import numpy as np
import xarray as xr

from railradio import plotting

STYLE = {"joint": ("o", "C0", "joint decision"), "distance": ("^", "C2", "distance trigger")}


def plot_success_vs_sigma(summ: xr.Dataset, pdf_path, png_path=None, figure_max_sigma_m: float = 20.0) -> None:
    """Left: σ ∈ [0, figure_max_sigma_m]; right: the whole σ grid (log axis) with the
    crossover.  Joint and distance with 95 % intervals, A3 as a horizontal band, the
    nr-driven points at their RMS error.

    Parameters
    ----------
    summ : xarray.Dataset
        The chain summary (:func:`railradio.chain.summary.summarize`): ``success``,
        ``success_lo``, ``success_hi`` [1] over (input, policy), ``err_rms_m`` [m] and
        ``sigma_m`` [m] over input, ``speed_kmh`` [km/h].  A3's band is taken at the
        Gauss–Markov input of the smallest σ.
    pdf_path : str or os.PathLike
        Path of the PDF.
    png_path : str or os.PathLike or None, default None
        Path of the PNG; None: ``pdf_path`` with the suffix ``.png``.
    figure_max_sigma_m : float, default 20.0
        Largest σ of the left (linear) panel [m].

    Returns
    -------
    None
        The figure is written to ``pdf_path`` and ``png_path``.
    """
    fig, axes = plotting.figure(ncols=2, figsize=(8.0, 3.4), sharey=True)
    gm = summ.where(np.isfinite(summ["sigma_m"]), drop=True).sortby("sigma_m")
    sig = gm["sigma_m"].values
    ref = gm["input"].values[0]
    a3 = float(summ["success"].sel(policy="a3", input=ref))
    a3_lo, a3_hi = (float(summ[f"success_{b}"].sel(policy="a3", input=ref)) for b in ("lo", "hi"))
    nr_labels = [str(i) for i in summ["input"].values if str(i).startswith("nr_")]
    for ax, sel, xs in ((axes[0], sig <= figure_max_sigma_m, "linear"), (axes[1], sig > 0, "log")):
        ax.axhspan(a3_lo, a3_hi, color="0.8", lw=0)
        ax.axhline(a3, color="black", ls="--", lw=1.0, label="A3 event (position-free)")
        for p, (marker, color, label) in STYLE.items():
            y = gm["success"].sel(policy=p).values[sel]
            lo = gm["success_lo"].sel(policy=p).values[sel]
            hi = gm["success_hi"].sel(policy=p).values[sel]
            ax.fill_between(sig[sel], lo, hi, color=color, alpha=0.25, lw=0)
            ax.plot(sig[sel], y, marker=marker, color=color, markerfacecolor="none", label=f"{label}, Gauss–Markov σ")
            for lab in nr_labels:
                x = float(summ["err_rms_m"].sel(input=lab))
                if xs == "log":
                    continue
                yy = float(summ["success"].sel(input=lab, policy=p))
                e = np.array(
                    [
                        [yy - float(summ["success_lo"].sel(input=lab, policy=p))],
                        [float(summ["success_hi"].sel(input=lab, policy=p)) - yy],
                    ]
                )
                ax.errorbar(
                    [x],
                    [yy],
                    yerr=e,
                    marker="*",
                    ms=11,
                    color=color,
                    ls="none",
                    markeredgecolor="black",
                    label=f"{label}, 5G NR {lab[3:].upper()} position",
                )
        ax.set_xscale(xs)
        ax.set_xlabel(r"along-track position error $\sigma$ [m]")
    axes[0].set_ylabel(f"handover success at {float(summ['speed_kmh']):g} km/h")
    axes[0].set_title(f"σ ≤ {figure_max_sigma_m:g} m", fontsize="small")
    axes[1].set_title("whole sweep", fontsize="small")
    axes[0].legend(fontsize="x-small", loc="lower left")
    plotting.save(fig, pdf_path, png_path)
