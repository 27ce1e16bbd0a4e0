"""Figures of the fusion study (source 002, Fig. 3–5): RMSE against the swept parameter,
TDOA, AOA, both fusions and the CRLB."""

from __future__ import annotations

import numpy as np
import xarray as xr

from railradio import plotting
from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.fusion.montecarlo import ESTIMATOR_LABELS

SWEEP_AXES = {
    "d_m": ("BS distance from the track $d$ [m]", 1.0),
    "sigma_tdoa_s": (r"TDOA error std $c\,\sigma_\mathrm{TDOA}$ [m]", SPEED_OF_LIGHT_M_S),
    "sigma_aoa_rad": (r"AOA error std $\sigma_\mathrm{AOA}$ [rad]", 1.0),
}
MARKERS = {"tdoa": "o", "aoa": "s", "fused_genie": "^", "fused_propagated": "v"}


def plot_sweep(ds: xr.Dataset, parameter: str, pdf_path: str, png_path: str | None = None, log_y: bool = True) -> None:
    """Plot one sweep dataset (:func:`railradio.fusion.sweep_dataset`) to PDF and PNG.

    Error bars are ±2 Monte Carlo standard errors (mostly smaller than the markers).

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep dataset: ``rmse``, ``rmse_se`` [m] over (estimator, ``parameter``) and
        ``crlb_m`` [m] over ``parameter``.
    parameter : {"d_m", "sigma_tdoa_s", "sigma_aoa_rad"}
        The swept coordinate; the x axis shows d [m], c·σ_TDOA [m] (σ_TDOA [s] times the
        speed of light) or σ_AOA [rad].
    pdf_path : str
        Path of the PDF.
    png_path : str or None, default None
        Path of the PNG; None: ``pdf_path`` with the suffix ``.png``.
    log_y : bool, default True
        Logarithmic RMSE axis.

    Returns
    -------
    None
        The figure is written to ``pdf_path`` and ``png_path``.

    Raises
    ------
    ValueError
        If ``parameter`` is not one of the three swept coordinates.
    """
    if parameter not in SWEEP_AXES:
        raise ValueError(f"parameter must be one of {sorted(SWEEP_AXES)}, got {parameter!r}")
    label, scale = SWEEP_AXES[parameter]
    x = np.asarray(ds[parameter].values) * scale
    fig, ax = plotting.figure()
    for est in ds["estimator"].values:
        y = ds["rmse"].sel(estimator=est).values
        se = ds["rmse_se"].sel(estimator=est).values
        ax.errorbar(
            x,
            y,
            yerr=2 * se,
            marker=MARKERS[str(est)],
            label=ESTIMATOR_LABELS[str(est)],
            capsize=2,
            markerfacecolor="none",
        )
    # on top: where the fusion attains the bound its markers would hide it
    ax.plot(x, ds["crlb_m"].values, label="CRLB", zorder=5, **plotting.BOUND_STYLE)
    ax.set_xlabel(label)
    ax.set_ylabel("position RMSE [m]")
    if log_y:
        plotting.log_axis(ax, "y")
    ax.legend()
    plotting.save(fig, pdf_path, png_path)
