"""Key numbers of the fusion study (docs/model/fusion.md; the source states none numerically)."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from railradio.fusion.montecarlo import summarize
from railradio.keynumbers import KeySpec

SPECS = {
    "fusion.d1500.rmse_tdoa_m": KeySpec("fusion.d1500.rmse_tdoa_m", "m", "TDOA-on-track RMSE, d = 1500 m"),
    "fusion.d1500.rmse_aoa_m": KeySpec("fusion.d1500.rmse_aoa_m", "m", "AOA-on-track RMSE, d = 1500 m"),
    "fusion.d1500.rmse_fused_m": KeySpec(
        "fusion.d1500.rmse_fused_m", "m", "fused RMSE (MC variances, the source's reading), d = 1500 m"
    ),
    "fusion.d1500.rmse_fused_propagated_m": KeySpec(
        "fusion.d1500.rmse_fused_propagated_m", "m", "fused RMSE (propagated variances), d = 1500 m"
    ),
    "fusion.d1500.crlb_m": KeySpec("fusion.d1500.crlb_m", "m", "CRLB on the track, d = 1500 m"),
    "fusion.claim.fused_below_both_frac": KeySpec(
        "fusion.claim.fused_below_both_frac", "1", "share of sweep points where fusion beats TDOA and AOA", 1.0, "="
    ),
    "fusion.claim.tdoa_d_ratio": KeySpec(
        "fusion.claim.tdoa_d_ratio", "1", "TDOA RMSE max/min over the d sweep (flat: near 1)"
    ),
    "fusion.claim.aoa_d_ratio": KeySpec(
        "fusion.claim.aoa_d_ratio", "1", "AOA RMSE at the largest over the smallest d (grows with d)"
    ),
    "fusion.claim.tdoa_no_solution_frac_dmin": KeySpec(
        "fusion.claim.tdoa_no_solution_frac_dmin", "1", "share of TDOA trials without solution at the smallest d swept"
    ),
    "fusion.claim.fused_over_crlb_max": KeySpec(
        "fusion.claim.fused_over_crlb_max", "1", "largest fused-RMSE/CRLB ratio over all sweep points", digits=4
    ),
}


def key_numbers(reference: xr.Dataset, sweeps: dict[str, xr.Dataset]) -> dict[str, Any]:
    """Key numbers from the reference point and the three sweep datasets.

    Parameters
    ----------
    reference : xarray.Dataset
        The :func:`~railradio.fusion.montecarlo.simulate_point` dataset of the reference
        point (the key names ``fusion.d1500.*`` assume the config's d = 1500 m).
    sweeps : dict of str to xarray.Dataset
        Config sweep name (``"d_m"``, ``"sigma_tdoa_us"``, ``"sigma_aoa_rad"``) -> its
        :func:`~railradio.fusion.montecarlo.sweep_dataset`; ``"d_m"`` must be present.

    Returns
    -------
    dict of str to dict
        Key name ``fusion.*`` (:data:`SPECS`) -> its JSON entry
        (:meth:`railradio.keynumbers.KeySpec.entry`: ``value``, ``unit``, ``source_value``,
        ``source_relation``, ``description``, ``mc_stderr``, ``digits``): RMSEs and CRLB at
        the reference point [m] (with Monte Carlo standard errors), and the claims' shares
        and ratios [1].
    """
    s = summarize(reference)
    out = {
        "fusion.d1500.rmse_tdoa_m": SPECS["fusion.d1500.rmse_tdoa_m"].entry(s["rmse_tdoa_m"], s["rmse_tdoa_se_m"]),
        "fusion.d1500.rmse_aoa_m": SPECS["fusion.d1500.rmse_aoa_m"].entry(s["rmse_aoa_m"], s["rmse_aoa_se_m"]),
        "fusion.d1500.rmse_fused_m": SPECS["fusion.d1500.rmse_fused_m"].entry(
            s["rmse_fused_genie_m"], s["rmse_fused_genie_se_m"]
        ),
        "fusion.d1500.rmse_fused_propagated_m": SPECS["fusion.d1500.rmse_fused_propagated_m"].entry(
            s["rmse_fused_propagated_m"], s["rmse_fused_propagated_se_m"]
        ),
        "fusion.d1500.crlb_m": SPECS["fusion.d1500.crlb_m"].entry(s["crlb_m"], 0.0),
    }
    below, total, ratio_max = 0, 0, 0.0
    for ds in sweeps.values():
        rmse = ds["rmse"]
        fused = rmse.sel(estimator="fused_genie").values
        best_single = np.minimum(rmse.sel(estimator="tdoa").values, rmse.sel(estimator="aoa").values)
        below += int(np.sum(fused < best_single))
        total += fused.size
        ratio_max = max(ratio_max, float(np.max(fused / ds["crlb_m"].values)))
    d = sweeps["d_m"]
    tdoa_d = d["rmse"].sel(estimator="tdoa").values
    aoa_d = d["rmse"].sel(estimator="aoa").values
    out["fusion.claim.fused_below_both_frac"] = SPECS["fusion.claim.fused_below_both_frac"].entry(below / total)
    out["fusion.claim.tdoa_d_ratio"] = SPECS["fusion.claim.tdoa_d_ratio"].entry(float(tdoa_d.max() / tdoa_d.min()))
    out["fusion.claim.aoa_d_ratio"] = SPECS["fusion.claim.aoa_d_ratio"].entry(float(aoa_d[-1] / aoa_d[0]))
    out["fusion.claim.tdoa_no_solution_frac_dmin"] = SPECS["fusion.claim.tdoa_no_solution_frac_dmin"].entry(
        float(d["frac_tdoa_no_solution"].values[0])
    )
    out["fusion.claim.fused_over_crlb_max"] = SPECS["fusion.claim.fused_over_crlb_max"].entry(ratio_max)
    return out
