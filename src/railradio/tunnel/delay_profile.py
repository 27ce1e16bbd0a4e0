"""The local-mean power delay profile of all slots at a receiver and its RMS delay spread,
with and without a dynamic-range threshold (docs/model/tunnel.md §2.3).

Measurement campaigns compute the RMS delay spread from a profile cut at a fixed level below
its peak (commonly 25 or 30 dB), because the receiver's noise floor and dynamic range end
there; the unthresholded spread counts every arrival however weak, which a measurement
cannot.  Far slots arrive microseconds late and 30-60 dB down, so the two differ most here.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from railradio.tunnel.channel import moving_mean, offset_index, slot_powers, window_samples, window_slots
from railradio.tunnel.geometry import Cable, Tunnel


def slot_pdp(table: xr.Dataset) -> np.ndarray:
    """Each offset's local-mean power delay profile [offset, excess-delay bin] [1], summing to
    the table's local mean ``power_mean``.

    Physical tables: the taps' power averaged over the local-mean window (mirrored at 0), the
    same average as the table's delay moments; the source's model: the taps' power.

    Parameters
    ----------
    table : xarray.Dataset
        Tabulated channel (:func:`railradio.tunnel.channel.tabulate`): ``taps``
        [offset_m, excess_delay_s], ``power_mean`` [offset_m], attributes ``propagation``
        and ``local_mean_window_m`` [m].

    Returns
    -------
    numpy.ndarray
        Power per excess-delay bin relative to the cable power at the slot [offset, bin].
    """
    p = np.abs(table["taps"].values) ** 2
    if table.attrs["propagation"] == "physical":
        off = table["offset_m"].values
        step = off[1] - off[0] if off.size > 1 else 1.0
        p = moving_mean(p, window_samples(float(table.attrs["local_mean_window_m"]), step), mirror_start=True)
    tot = p.sum(axis=1)
    scale = np.divide(table["power_mean"].values, tot, out=np.zeros_like(tot), where=tot > 0)
    return p * scale[:, None]


def rms_spread_s(pdp: np.ndarray, delay_s: np.ndarray, threshold_db: float | None = None) -> np.ndarray:
    """RMS delay spread of power delay profiles [s], optionally counting only the bins within
    ``threshold_db`` of each profile's peak.

    Parameters
    ----------
    pdp : numpy.ndarray
        Power delay profiles [profile, bin] [any power unit], non-negative.
    delay_s : numpy.ndarray
        Delay of every bin [bin] [s].
    threshold_db : float or None
        Dynamic range below the peak [dB], positive; None: every bin counts.

    Returns
    -------
    numpy.ndarray
        RMS delay spread [profile] [s] (0 for an all-zero profile).

    Raises
    ------
    ValueError
        When ``threshold_db`` is not positive.
    """
    p = np.asarray(pdp, dtype=float)
    if threshold_db is not None:
        if not threshold_db > 0:
            raise ValueError(f"threshold_db must be positive, got {threshold_db!r}")
        p = np.where(p >= p.max(axis=1, keepdims=True) * 10.0 ** (-threshold_db / 10.0), p, 0.0)
    tot = p.sum(axis=1)
    safe = np.where(tot > 0, tot, 1.0)
    m1 = p @ delay_s / safe
    m2 = p @ (delay_s**2) / safe
    return np.sqrt(np.maximum(m2 - m1**2, 0.0))


def received_spreads(
    table: xr.Dataset,
    tunnel: Tunnel,
    cable: Cable,
    x_rx_m: np.ndarray,
    thresholds_db: tuple[float, ...] = (25.0, 30.0),
    chunk: int = 256,
) -> dict[float | None, np.ndarray]:
    """RMS delay spread of the local-mean power delay profile of all slots (cable delays
    included) at receiver positions, without and with each dynamic-range threshold [s].

    Every slot within the table's range adds its :func:`slot_pdp` at its offset, delayed by
    its cable delay plus the line-of-sight delay, on the table's excess-delay grid (absolute
    delays rounded to that grid).

    Parameters
    ----------
    table : xarray.Dataset
        Tabulated slot-to-receiver channel (uniform ``offset_m`` grid from 0; ``excess_delay_s``
        a uniform grid; ``los_delay_s`` [offset_m] [s]).
    tunnel : Tunnel
        Slot positions and tunnel length.
    cable : Cable
        Cable power and delay at each slot.
    x_rx_m : numpy.ndarray
        Receiver positions along the tunnel [m], 1-D.
    thresholds_db : tuple of float
        Dynamic ranges below the peak [dB], each positive.
    chunk : int
        Receivers evaluated at a time (memory only).

    Returns
    -------
    dict
        None (no threshold) and every threshold [dB] -> RMS delay spread [receiver] [s].
    """
    xs, pc_dbm, tc = slot_powers(tunnel, cable)
    pw_c = 10.0 ** ((pc_dbm - 30.0) / 10.0)
    pdp = slot_pdp(table)
    exc = table["excess_delay_s"].values
    dt = float(exc[1] - exc[0]) if exc.size > 1 else 1e-8
    los = table["los_delay_s"].values
    n_b = exc.size
    max_off = float(table["offset_m"].values[-1])
    start_bin = np.rint((tc.max() + los.max()) / dt).astype(np.int64)
    n_grid = int(start_bin) + n_b + 1
    delay = np.arange(n_grid) * dt
    x_all = np.asarray(x_rx_m, dtype=float)
    keys = (None, *thresholds_db)
    out = {k: np.empty(x_all.size) for k in keys}
    for a in range(0, x_all.size, chunk):
        x = x_all[a : a + chunk]
        sl, ok = window_slots(tunnel, x, max_off)
        idx, inside = offset_index(table, x[:, None] - xs[sl])
        w = pw_c[sl] * (ok & inside)  # [rx, slot]
        b0 = np.rint((tc[sl] + los[idx]) / dt).astype(np.int64)  # [rx, slot]
        rows = np.arange(x.size)[:, None, None] * n_grid
        flat = (rows + b0[..., None] + np.arange(n_b)[None, None, :]).ravel()
        prof = np.bincount(flat, weights=(w[..., None] * pdp[idx]).ravel(), minlength=x.size * n_grid)
        prof = prof.reshape(x.size, n_grid)
        for k in keys:
            out[k][a : a + chunk] = rms_spread_s(prof, delay, k)
    return out


def delay_spread_note(threshold_db: float | None) -> str:
    """The long name of a thresholded (or not) delay spread variable."""
    if threshold_db is None:
        return "RMS delay spread of the local-mean power delay profile of all slots, every arrival counted"
    return (
        "RMS delay spread of the local-mean power delay profile of all slots, bins more than "
        f"{threshold_db:g} dB below its peak dropped (a measurement's dynamic range)"
    )
