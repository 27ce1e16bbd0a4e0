"""Figure ``fusion_sensitivity``: (a) RMSE against the track curvature, straight-line vs arc
constraint; (b) RMSE against the TDOA error correlation, independent vs whitened weighting;
each with its Cramér–Rao bound."""

from __future__ import annotations

import numpy as np
import xarray as xr

from railradio import plotting

CURVE_STYLE = {
    "mismatch_fused": {"marker": "o", "label": "straight-line constraint (mismatch)"},
    "arc_fused": {"marker": "^", "label": "arc constraint"},
}
RHO_STYLE = {
    "one_tdoa": {"marker": "s", "label": "one TDOA (the source's)"},
    "naive": {"marker": "o", "label": "two TDOAs, weighted as independent"},
    "whitened": {"marker": "^", "label": "two TDOAs, whitened"},
}


def plot_sensitivity(curve: xr.Dataset, rho: xr.Dataset, pdf_path: str, png_path: str | None = None) -> None:
    """Two panels from the sweep datasets of :func:`railradio.fusion.sensitivity.sens_sweep_dataset`.

    Error bars are ±2 Monte Carlo standard errors (mostly smaller than the markers).

    Parameters
    ----------
    curve : xarray.Dataset
        The curvature sweep (dimension ``curvature_per_m`` [1/m]; estimators
        ``mismatch_fused``, ``arc_fused``): panel (a), x axis in 1/km.
    rho : xarray.Dataset
        The correlation sweep (dimension ``rho`` [1]; estimators ``one_tdoa``, ``naive``,
        ``whitened``): panel (b).
    pdf_path : str
        Path of the PDF.
    png_path : str or None, default None
        Path of the PNG; None: ``pdf_path`` with the suffix ``.png``.

    Returns
    -------
    None
        The figure is written to ``pdf_path`` and ``png_path``.

    Raises
    ------
    ValueError
        If ``curve`` has no dimension ``curvature_per_m`` or ``rho`` no dimension ``rho``.
    """
    if "curvature_per_m" not in curve.dims or "rho" not in rho.dims:
        raise ValueError("curve must be the curvature sweep and rho the correlation sweep")
    fig, (ax_c, ax_r) = plotting.figure(ncols=2, figsize=(9.0, 3.6))
    k_per_km = np.asarray(curve["curvature_per_m"].values) * 1e3
    for est, style in CURVE_STYLE.items():
        ax_c.errorbar(
            k_per_km,
            curve["rmse"].sel(estimator=est).values,
            yerr=2 * curve["rmse_se"].sel(estimator=est).values,
            capsize=2,
            markerfacecolor="none",
            **style,
        )
    ax_c.plot(k_per_km, curve["crlb_m"].values, label="CRLB (on the arc)", **plotting.BOUND_STYLE)
    plotting.log_axis(ax_c, "y")
    ax_c.set_xlabel(r"track curvature $1/R_\mathrm{arc}$ [km$^{-1}$]")
    ax_c.set_ylabel("along-track RMSE [m]")
    top = ax_c.secondary_xaxis("top")
    top.set_xticks(k_per_km)
    top.set_xticklabels([r"$\infty$" if k == 0 else f"{1.0 / k:g}" for k in k_per_km], fontsize="small")
    top.set_xlabel(r"track radius $R_\mathrm{arc}$ [km]", fontsize="small")
    ax_c.set_title("(a) curved track", loc="left", fontsize="medium")
    ax_c.legend(fontsize="small")

    r = np.asarray(rho["rho"].values)
    for est, style in RHO_STYLE.items():
        ax_r.errorbar(
            r,
            rho["rmse"].sel(estimator=est).values,
            yerr=2 * rho["rmse_se"].sel(estimator=est).values,
            capsize=2,
            markerfacecolor="none",
            **style,
        )
    ax_r.plot(r, rho["crlb_m"].values, label="CRLB (correlated)", **plotting.BOUND_STYLE)
    ax_r.set_xlabel(r"TDOA error correlation $\rho$")
    ax_r.set_ylabel("position RMSE [m]")
    ax_r.set_ylim(bottom=0)
    ax_r.set_title("(b) correlated TDOA errors", loc="left", fontsize="medium")
    ax_r.legend(fontsize="small")
    fig.tight_layout()
    plotting.save(fig, pdf_path, png_path)
