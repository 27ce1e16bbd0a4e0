"""The sensitivity cases of the tunnel study: one train type through measurement models changed
one thing at a time from the defaults (shadowing and delay-error sigma, the delay-error model,
the cable on the side wall)."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from railradio.tunnel.simulate import calibrate_separable, kf_realizations
from railradio.tunnel.study import (
    cable_from_config,
    measurement_from_config,
    side_wall_config,
    train_from_config,
    tunnel_from_config,
)


def case_label(v: float) -> str:
    """A sweep value as a case-name fragment: 3.5 -> "3p5", -1 -> "m1".

    Parameters
    ----------
    v : float
        The swept value, in the unit of its ``sensitivity`` entry (e.g. dB, ns).

    Returns
    -------
    str
        ``v`` in ``%g`` format with '.' written 'p' and '-' written 'm'.
    """
    return f"{v:g}".replace(".", "p").replace("-", "m")


def sensitivity_cases(cfg: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Sensitivity cases (shadowing and delay-error sigma swept over the source's
    ranges; the delay-error model): label -> overrides of the measurement section, each
    case changing one thing from the defaults, and the delay-sigma sweep repeated with each
    correlated delay-error model (``delay_sigma_ns_<v>_<model>``).

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration; ``sensitivity`` holds the swept
        ``shadow_sigma_db`` [dB] and ``delay_sigma_ns`` [ns] values and the
        ``delay_errors`` models (``white``, ``ar1``, ``slot_bias``).

    Returns
    -------
    dict
        Case label (``shadow_sigma_db_<v>``, ``delay_sigma_ns_<v>``, ``delay_error_<model>``,
        ``delay_sigma_ns_<v>_<model>``; in ``<v>`` a '.' is written 'p' and a '-' 'm') ->
        keyword overrides for :func:`railradio.tunnel.study.measurement_from_config`, in
        the units of the ``measurement`` section.
    """
    sv = cfg["sensitivity"]
    cases: dict[str, dict[str, Any]] = {}
    for v in sv["shadow_sigma_db"]:
        cases[f"shadow_sigma_db_{case_label(v)}"] = {"shadow_sigma_db": float(v)}
    for v in sv["delay_sigma_ns"]:
        cases[f"delay_sigma_ns_{case_label(v)}"] = {"delay_sigma_ns": float(v)}
    for e in sv["delay_errors"]:
        cases[f"delay_error_{e}"] = {"delay_error": e}
    for e in sv["delay_errors"]:  # the delay-sigma sweep with each correlated error model
        if e != "white":
            for v in sv["delay_sigma_ns"]:
                cases[f"delay_sigma_ns_{case_label(v)}_{e}"] = {"delay_sigma_ns": float(v), "delay_error": e}
    return cases


def make_sensitivity(
    cfg: dict[str, Any], table: xr.Dataset, train_name: str, seed: int, side_wall_table: xr.Dataset | None = None
) -> xr.Dataset:
    """One train type through every sensitivity case: physical channel, separable receiver,
    head and tail KF, ``cfg['realizations']`` Monte Carlo realizations (the same fields and
    noise as the main run, so the default case reproduces it).  Per case: the pooled 95th
    percentile of the train error and the availabilities, and each realization's 95th
    percentile (their spread gives the Monte Carlo standard error).  With ``side_wall_table``
    (the channel with the cable on the side wall) also the case ``slot_side_wall``: default
    measurements, that geometry and channel.

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration (``geometry``, ``cable``, ``wall``,
        ``rays``, ``source_model``, ``measurement``, ``trains``, ``positioning``,
        ``tracking``, ``realizations``, ``sensitivity``).
    table : xarray.Dataset
        The physical channel table of the configured engine
        (:func:`railradio.tunnel.study.make_table`).
    train_name : str
        Train type, a key of ``cfg['trains']``.
    seed : int
        Root seed of the workflow (the same random streams as the main run).
    side_wall_table : xarray.Dataset or None
        The engine's table with the cable on the side wall; None leaves out ``slot_side_wall``.

    Returns
    -------
    xarray.Dataset
        Over ``case`` (labels of :func:`sensitivity_cases`, then ``slot_side_wall``):
        ``err_p95_m`` (pooled 95th percentile of the KF train error) [m], ``avail_lt_5m``
        and ``avail_lt_2m`` (share of epochs with train error below 5 m, 2 m) [1];
        ``rep_err_p95_m`` [case, realization] (each realization's 95th percentile) [m].
        Attribute ``train``.

    Raises
    ------
    ValueError
        When a case gives an invalid measurement model, or too few slots lie within the
        measurement window.
    """
    tun = tunnel_from_config(cfg, table.attrs["shape"])
    cab = cable_from_config(cfg)
    train = train_from_config(cfg, train_name)
    n_r = cfg["realizations"]
    cases = {k: (v, tun, table) for k, v in sensitivity_cases(cfg).items()}
    if side_wall_table is not None:
        cases["slot_side_wall"] = (
            {},
            tunnel_from_config(side_wall_config(cfg), side_wall_table.attrs["shape"]),
            side_wall_table,
        )
    p95 = np.empty((len(cases), n_r))
    pooled = np.empty((len(cases), 3))
    for i, (over, tu, tab) in enumerate(cases.values()):
        mm = measurement_from_config(cfg, **over)
        r0 = calibrate_separable(tab, tu, cab, train, mm, "physical", cfg["tracking"], seed)
        eh, et = kf_realizations(tab, tu, cab, train, mm, "physical", cfg["tracking"], seed, r0, range(n_r))
        err = np.sqrt((eh**2 + et**2) / 2.0)
        p95[i] = np.percentile(err, 95, axis=1)
        pooled[i] = np.percentile(err, 95), np.mean(err < 5.0), np.mean(err < 2.0)
    dims = ("case",)
    return xr.Dataset(
        {
            "err_p95_m": (
                dims,
                pooled[:, 0],
                {"units": "m", "long_name": "95th pct of the KF train error, pooled over realizations"},
            ),
            "avail_lt_5m": (dims, pooled[:, 1], {"units": "1", "long_name": "share of epochs with train error < 5 m"}),
            "avail_lt_2m": (dims, pooled[:, 2], {"units": "1", "long_name": "share of epochs with train error < 2 m"}),
            "rep_err_p95_m": (
                ("case", "realization"),
                p95,
                {"units": "m", "long_name": "95th pct of the KF train error per realization"},
            ),
        },
        coords={
            "case": ("case", list(cases), {"units": "1", "long_name": "sensitivity case"}),
            "realization": ("realization", np.arange(n_r), {"units": "1", "long_name": "Monte Carlo realization"}),
        },
        attrs={"train": train_name},
    )
