"""Key numbers ``sens.fusion.*`` of the fusion sensitivity sweeps (docs/model/fusion.md §5; the source has none).

Names (R in metres as an integer, ``inf`` for the straight base; ρ as written by ``{:g}``):

* ``sens.fusion.curve_r{R}.mismatch.rmse_m`` — fused RMSE keeping the straight-line constraint
* ``sens.fusion.curve_r{R}.mismatch.bias_m`` — its RMS over positions of the mean error
* ``sens.fusion.curve_r{R}.arc.rmse_m`` — fused RMSE with the arc as the constraint
* ``sens.fusion.curve_r{R}.crlb_m`` — the on-arc CRLB, sqrt(mean 1/J(s))
* ``sens.fusion.curve_r{R}.sagitta_m`` — offset of the arc from its tangent at s = L
* ``sens.fusion.rho{ρ}.naive.rmse_m`` — two TDOAs weighted as independent
* ``sens.fusion.rho{ρ}.whitened.rmse_m`` — two TDOAs weighted with the correlation (BLUE)
* ``sens.fusion.rho{ρ}.crlb_m`` — the CRLB with the correlated covariance
* ``sens.fusion.one_tdoa.rmse_m`` — the source's estimator (one TDOA) on the same trials

e.g. ``sens.fusion.curve_r4000.arc.rmse_m``, ``sens.fusion.rho0.5.whitened.rmse_m``.  Dots
and digits are fine in the LaTeX macros (``\\kn{...}`` looks names up with ``\\csname``).
"""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np
import xarray as xr

from railradio.keynumbers import KeySpec

_NAME_RE = re.compile(r"^[a-z0-9_.]+$")


def radius_tag(radius_m: float) -> str:
    """``r4000`` for R = 4000 m, ``rinf`` for the straight track.

    Parameters
    ----------
    radius_m : float
        Track radius of curvature R [m]; ``math.inf`` for the straight track.

    Returns
    -------
    str
        ``"rinf"`` for an infinite radius, ``"r"`` followed by R as an integer when R is a
        whole number of metres, else ``"r"`` followed by ``repr(R)`` (e.g. ``r4000.5``).
    """
    if math.isinf(radius_m):
        return "rinf"
    if radius_m == int(radius_m):
        return f"r{int(radius_m)}"
    return f"r{radius_m!r}"


def rho_tag(rho: float) -> str:
    """``rho0.5`` for ρ = 0.5, ``rho0`` for ρ = 0.

    Parameters
    ----------
    rho : float
        Correlation coefficient ρ of the two TDOA errors [1].

    Returns
    -------
    str
        ``"rho"`` followed by ρ formatted with ``{:g}``.
    """
    return f"rho{float(rho):g}"


def _spec(name: str, unit: str, description: str, digits: int = 3) -> KeySpec:
    if not _NAME_RE.match(name):
        raise ValueError(f"key name {name!r} has characters unsafe for the LaTeX macros")
    return KeySpec(name, unit, description, digits=digits)


def key_numbers(curve: xr.Dataset, rho: xr.Dataset) -> dict[str, Any]:
    """Key numbers from the two sweep datasets of :func:`railradio.fusion.sensitivity.sens_sweep_dataset`.

    Parameters
    ----------
    curve : xarray.Dataset
        The ``curve`` sweep (along ``curvature_per_m`` [1/m]).
    rho : xarray.Dataset
        The ``rho`` sweep (along ``rho`` [1]).

    Returns
    -------
    dict of str to dict
        Key name ``sens.fusion.*`` (module docstring) -> its JSON entry
        (:meth:`railradio.keynumbers.KeySpec.entry`: ``value``, ``unit``, ``source_value``,
        ``source_relation``, ``description``, ``mc_stderr``, ``digits``); RMSEs (with Monte
        Carlo standard errors), RMS biases, CRLBs and sagittas, all in m.

    Raises
    ------
    ValueError
        If the ``one_tdoa`` RMSE differs along the ρ sweep (common random numbers broken), or
        a key name has characters unsafe for the LaTeX macros (e.g. a negative ρ).
    """
    out: dict[str, Any] = {}
    d = float(curve["d_m"].values[0])
    for i in range(curve.sizes["curvature_per_m"]):
        c = curve.isel(curvature_per_m=i)
        r = float(c["radius_m"])
        r_text = "straight track" if math.isinf(r) else f"R = {r:g} m"
        pre = f"sens.fusion.curve_{radius_tag(r)}"
        rm, ra = c["rmse"].sel(estimator="mismatch_fused"), c["rmse"].sel(estimator="arc_fused")
        se_m, se_a = c["rmse_se"].sel(estimator="mismatch_fused"), c["rmse_se"].sel(estimator="arc_fused")
        items = [
            (
                f"{pre}.mismatch.rmse_m",
                "m",
                f"fused RMSE, straight-line constraint on a curved track, {r_text}, d = {d:g} m",
                float(rm),
                float(se_m),
            ),
            (
                f"{pre}.mismatch.bias_m",
                "m",
                f"RMS bias of the fused straight-line estimate, {r_text}",
                float(c["bias_rms"].sel(estimator="mismatch_fused")),
                None,
            ),
            (f"{pre}.arc.rmse_m", "m", f"fused RMSE, arc constraint, {r_text}", float(ra), float(se_a)),
            (f"{pre}.crlb_m", "m", f"CRLB on the along-track coordinate, {r_text}", float(c["crlb_m"]), 0.0),
            (
                f"{pre}.sagitta_m",
                "m",
                f"offset of the arc from its tangent at the cell's far train position, {r_text}",
                float(c["sagitta_m"]),
                None,
            ),
        ]
        for name, unit, desc, value, se in items:
            out[name] = _spec(name, unit, desc).entry(value, se)
    for i in range(rho.sizes["rho"]):
        c = rho.isel(rho=i)
        v = float(c["rho"])
        pre = f"sens.fusion.{rho_tag(v)}"
        for est, desc in (
            ("naive", "two TDOAs weighted as independent"),
            ("whitened", "two TDOAs weighted with their correlation (BLUE)"),
        ):
            name = f"{pre}.{est}.rmse_m"
            out[name] = _spec(name, "m", f"fused RMSE, {desc}, TDOA error correlation {v:g}").entry(
                float(c["rmse"].sel(estimator=est)), float(c["rmse_se"].sel(estimator=est))
            )
        name = f"{pre}.crlb_m"
        out[name] = _spec(name, "m", f"CRLB with two TDOAs of error correlation {v:g} and the AOA").entry(
            float(c["crlb_m"]), 0.0
        )
    one = rho["rmse"].sel(estimator="one_tdoa").values
    one_se = rho["rmse_se"].sel(estimator="one_tdoa").values
    # common random numbers: the source's one-TDOA estimator sees the same errors at every ρ
    if not np.allclose(one, one[0], rtol=1e-12, atol=0.0):
        raise ValueError("the one-TDOA RMSE differs along the rho sweep: common random numbers broken")
    name = "sens.fusion.one_tdoa.rmse_m"
    out[name] = _spec(name, "m", "fused RMSE of the source's estimator (one TDOA) on the rho sweep's trials").entry(
        float(one[0]), float(one_se[0])
    )
    return out
