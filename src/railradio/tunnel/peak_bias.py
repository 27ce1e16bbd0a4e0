"""Where the wideband receiver's peak-delay bias comes from: the noiseless CIR-peak delay minus
the cable-point model delay along the tunnel, for channels from one slot's line of sight to the
full channel of every slot."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import xarray as xr

from railradio.tunnel.channel import tabulate
from railradio.tunnel.rays import image_families
from railradio.tunnel.study import cable_from_config, local_mean_window, measurement_from_config, tunnel_from_config
from railradio.tunnel.wideband import cable_model_delay_s, tone_response, wideband_delays

PEAK_BIAS_CASES = ("single_slot", "los_slots", "full", "full_all_slots")
"""Noiseless wideband peak-delay offsets: the nearest slot's line-of-sight ray alone; every
slot's line-of-sight ray in the receiver's window (absorbing walls); the full channel in the
window (the receiver's model); the full channel of every tabulated slot."""


def make_peak_bias(cfg: dict[str, Any], table: xr.Dataset, step_m: float = 9.7) -> xr.Dataset:
    """Where the wideband receiver's peak-delay bias comes from: the noiseless CIR-peak delay
    minus the cable-point model delay (cable delay to x + h/c) at receivers every ``step_m``
    along the tunnel (not a divisor of the slot spacing: every offset to the nearest slot
    occurs), for the cases of :data:`PEAK_BIAS_CASES` (same estimator, same
    bandwidth and tones; the line-of-sight table has absorbing walls).

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration (``geometry``, ``cable``, ``wall``,
        ``rays``, ``measurement``: ``bandwidth_hz`` [Hz], ``n_tones``, ``window_m`` [m], ...).
    table : xarray.Dataset
        The physical channel table of the configured engine
        (:func:`railradio.tunnel.study.make_table`); its cross-section (attribute
        ``shape``) must be 'rect', because the line-of-sight table is built with the
        image method on its offsets.
    step_m : float
        Spacing of the receivers along the tunnel [m]; the receivers keep a margin from
        either end (the larger of the table's extent and ``measurement.window_m``, or
        ``window_m`` alone when the tunnel is shorter than twice that).

    Returns
    -------
    xarray.Dataset
        ``peak_bias_s`` [case, x_m]: noiseless CIR-peak delay minus the cable-point model
        delay [s]; ``case`` the labels of :data:`PEAK_BIAS_CASES`, ``x_m`` the receiver
        positions [m].  Attributes: ``bandwidth_hz`` [Hz], ``n_tones``, ``window_m`` [m].

    Raises
    ------
    ValueError
        When the table's cross-section is not 'rect'.
    """
    tun = tunnel_from_config(cfg, table.attrs["shape"])
    cab = cable_from_config(cfg)
    mm = measurement_from_config(cfg)
    r = cfg["rays"]
    los = tabulate(
        image_families(tun, 0),
        tun,
        cab,
        table["offset_m"].values,
        eps=None,
        polarization="paraxial",
        delay_bin_s=r["delay_bin_ns"] * 1e-9,
        n_delay_bins=r["n_delay_bins"],
        local_mean_window_m=local_mean_window(cfg),
    )
    extent = float(table["offset_m"].values[-1])
    margin = max(mm.window_m, extent)
    if tun.length_m <= 2 * margin:
        margin = mm.window_m
    x = np.arange(margin, tun.length_m - margin + 1e-9, step_m)
    cases = {
        "single_slot": (los, 0.5 * tun.slot_spacing_m - 1e-6),
        "los_slots": (los, mm.window_m),
        "full": (table, mm.window_m),
        "full_all_slots": (table, extent),
    }
    model = cable_model_delay_s(x, tun, cab)
    tones = {id(t): tone_response(t, mm) for t in (los, table)}
    bias = np.stack(
        [
            wideband_delays(
                t, tun, cab, x, None, dataclasses.replace(mm, window_m=w), tones=tones[id(t)], thermal_noise=False
            )
            - model
            for t, w in cases.values()
        ]
    )
    return xr.Dataset(
        {
            "peak_bias_s": (
                ("case", "x_m"),
                bias,
                {"units": "s", "long_name": "noiseless CIR-peak delay minus the cable-point model delay"},
            )
        },
        coords={
            "case": ("case", list(cases), {"units": "1", "long_name": "channel case"}),
            "x_m": ("x_m", x, {"units": "m", "long_name": "receiver position along the tunnel"}),
        },
        attrs={"bandwidth_hz": mm.bandwidth_hz, "n_tones": mm.n_tones, "window_m": mm.window_m},
    )
