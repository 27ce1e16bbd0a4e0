"""The separable receiver: every slot's RSSI and delay measured on their own, and the snapshot
fix from them (RSSI ranging + linearized LS, then TDOA Gauss-Newton) [source 4.2, 6.2]."""

from __future__ import annotations

import numpy as np
import xarray as xr

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.tunnel.channel import offset_index, slot_powers, window_slots
from railradio.tunnel.geometry import Cable, Tunnel
from railradio.tunnel.measurement import MeasurementModel, field_at
from railradio.tunnel.positioning import (
    gain_to_offset_m,
    gdop_source,
    gdop_tdoa_along,
    monotone_gain_db,
    range_diff_from_delays,
    rssi_ls,
    tdoa_gauss_newton,
)


def separable_measurements(
    table: xr.Dataset,
    tunnel: Tunnel,
    cable: Cable,
    x_rx_m: np.ndarray,
    shadow: np.ndarray,
    rng: np.random.Generator,
    mm: MeasurementModel,
    propagation: str,
    delay_field: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Per-slot RSSI and delay of the ``n_slots`` strongest measured slots [epoch, n];
    the delay error is white from ``rng`` or read from ``delay_field`` (see
    :func:`railradio.tunnel.measurement.delay_error_field`).

    Parameters
    ----------
    table : xarray.Dataset
        Tabulated slot-to-receiver channel (:func:`railradio.tunnel.channel.tabulate`):
        ``taps`` (physical) or ``power_mean`` (source) over ``offset_m`` [m].
    tunnel : Tunnel
        Slot positions and the cross distance h between slot line and receiver.
    cable : Cable
        Cable power at each slot.
    x_rx_m : numpy.ndarray
        Receiver positions along the tunnel [m], [epoch].
    shadow : numpy.ndarray
        Per-slot shadowing [slot, x on a 1 m grid] [dB]
        (:func:`railradio.tunnel.measurement.shadow_field`).
    rng : numpy.random.Generator
        Source of the white delay error (not used with ``delay_field``).
    mm : MeasurementModel
        ``n_slots``, ``window_m`` [m] and ``delay_sigma_s`` [s].
    propagation : {'physical', 'source'}
        'physical': a slot's gain is the power of its coherent tap sum; otherwise its
        local-mean power.
    delay_field : numpy.ndarray or None
        Per-slot delay error [slot, x on a 1 m grid] [s]; None: white.

    Returns
    -------
    dict
        Arrays [epoch, n_slots], the strongest slot first: ``slot`` (index), ``slot_x_m``
        [m], ``rssi_dbm`` [dBm], ``cable_power_dbm`` (cable power at the slot) [dBm],
        ``delay_s`` (slot-receiver line-of-sight delay plus its error) [s].

    Raises
    ------
    ValueError
        When fewer than ``n_slots`` slots lie within ``window_m`` and the table's extent
        of a receiver.
    """
    xs, pc_dbm, _ = slot_powers(tunnel, cable)
    x = np.asarray(x_rx_m, dtype=float)
    sl, ok = window_slots(tunnel, x, mm.window_m)
    idx, inside = offset_index(table, x[:, None] - xs[sl])
    if propagation == "physical":
        gain_db = 20.0 * np.log10(np.abs(table["taps"].values.sum(axis=1)))[idx]
    else:
        gain_db = 10.0 * np.log10(table["power_mean"].values)[idx]
    rssi = pc_dbm[sl] + gain_db + field_at(shadow, sl, x[:, None])
    rssi = np.where(ok & inside, rssi, -np.inf)
    order = np.argsort(-rssi, axis=1, kind="stable")[:, : mm.n_slots]
    pick = np.take_along_axis(sl, order, axis=1)
    rssi = np.take_along_axis(rssi, order, axis=1)
    if not np.all(np.isfinite(rssi)):
        raise ValueError(f"fewer than n_slots={mm.n_slots} slots within window_m={mm.window_m}")
    h = tunnel.cross_distance_m
    delay = np.sqrt((x[:, None] - xs[pick]) ** 2 + h * h) / SPEED_OF_LIGHT_M_S
    if delay_field is None:
        delay = delay + mm.delay_sigma_s * rng.standard_normal(pick.shape)
    else:
        delay = delay + field_at(delay_field, pick, np.broadcast_to(x[:, None], pick.shape))
    return {"slot": pick, "slot_x_m": xs[pick], "rssi_dbm": rssi, "cable_power_dbm": pc_dbm[pick], "delay_s": delay}


def separable_fix(meas: dict, table: xr.Dataset, tunnel: Tunnel, mm: MeasurementModel):
    """RSSI-LS fix, TDOA fix from it, its variance, both GDOPs [epoch].

    Parameters
    ----------
    meas : dict
        Measurements of :func:`separable_measurements`: ``slot_x_m`` [m], ``rssi_dbm`` and
        ``cable_power_dbm`` [dBm], ``delay_s`` [s], each [epoch, n].
    table : xarray.Dataset
        The channel table inverted for RSSI ranging (:func:`~railradio.tunnel.positioning.monotone_gain_db`).
    tunnel : Tunnel
        Cross distance h, tunnel length, receiver and slot heights.
    mm : MeasurementModel
        ``delay_sigma_s`` [s] (the TDOA weights).

    Returns
    -------
    tuple of numpy.ndarray
        ``(x_rssi, x_tdoa, sigma_tdoa, gdop_source, gdop_tdoa)``, each [epoch]: the RSSI-LS fix
        clipped to the tunnel [m], the TDOA Gauss-Newton fix started from it [m], the TDOA
        fix's standard deviation from its geometry (the square root of its variance) [m],
        the source's 2-D GDOP [1] and the along-track TDOA dilution [1].
    """
    h = tunnel.cross_distance_m
    off, curve = monotone_gain_db(table)
    dx = gain_to_offset_m(meas["rssi_dbm"] - meas["cable_power_dbm"], off, curve)
    x_rssi = rssi_ls(meas["slot_x_m"], np.sqrt(dx**2 + h * h), h)
    x_rssi = np.clip(x_rssi, 0.0, tunnel.length_m)
    sig = SPEED_OF_LIGHT_M_S * mm.delay_sigma_s
    x_tdoa, var = tdoa_gauss_newton(x_rssi, meas["slot_x_m"], range_diff_from_delays(meas["delay_s"]), h, sig)
    gd_source = gdop_source(x_tdoa, tunnel.rx_y_m, meas["slot_x_m"], tunnel.slot_yz[0])
    gd_tdoa = gdop_tdoa_along(x_tdoa, meas["slot_x_m"], h)
    return x_rssi, x_tdoa, np.sqrt(var), gd_source, gd_tdoa
