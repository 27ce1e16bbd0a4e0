"""The ray engines and the channel table checked: image method vs SBR in the square at fixed
offsets, one slot's far decay against the lossy modal sum of the square and of the circle
(where the retired SBR engine is measured against it), and whether the table reaches far
enough (its cut-off)."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from railradio.tunnel.channel import beat_length_m, coherent_gain_by_order, offset_grid_m, received, tabulate
from railradio.tunnel.lifting import lift
from railradio.tunnel.materials import circular_attenuation_db_per_m, eh11_attenuation_db_per_m
from railradio.tunnel.modes import circle_modal_gain, circle_modes, rect_modal_gain
from railradio.tunnel.rays import image_families
from railradio.tunnel.study import cable_from_config, eps_from_config, families, local_mean_window, tunnel_from_config


def _window_means_db(x_m: np.ndarray, p: np.ndarray, centres_m: np.ndarray, width_m: float) -> np.ndarray:
    """Mean of p [..., x] over windows of ``width_m`` centred at ``centres_m`` [dB, [..., centre]]."""
    return np.stack(
        [10.0 * np.log10(p[..., np.abs(x_m - c) <= width_m / 2.0].mean(axis=-1)) for c in centres_m], axis=-1
    )


def far_decay(cfg: dict[str, Any]) -> xr.Dataset:
    """One slot's local mean far from it, in the image-method tunnel, for every reflection
    order up to ``max_order``: the coherent power averaged over windows of one EH11-EH12
    beat length (:func:`railradio.tunnel.channel.beat_length_m`, which removes the beating
    of the two lowest modes) centred every quarter beat length over ``rays.far_decay_m``,
    and its least-squares slope, against the EH11 attenuation of the same square (Emslie,
    Lagace & Strong 1975).  The slope key takes the highest order; the order at which the
    window means are within 0.1 dB of it tells whether it converged.

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration (``geometry``, ``cable``, ``wall``,
        ``rays``; ``rays.max_order``, ``rays.far_decay_m``: the first and last window centre,
        offsets from the slot [m]).

    Returns
    -------
    xarray.Dataset
        ``local_mean_db`` [order, centre_m] (one slot's coherent power, unit EIRP, truncated
        at each reflection order and averaged over one beat length) [dB] and
        ``slope_db_per_km`` [order] (its least-squares decay over the centres) [dB/km];
        coordinates ``order`` (the highest reflection order summed) and ``centre_m`` (window
        centre, offset from the slot) [m].  Attributes: ``beat_length_m`` [m],
        ``eh11_db_per_km`` (EH11 attenuation of the square) [dB/km], ``converged_order``
        (the first order whose window means are all within 0.1 dB of the highest order's)
        ``slope_db_per_km`` (the slope at the highest order) [dB/km], ``modal_slope_db_per_km``
        (the same slope of the EH_mn modal sum for this slot and receiver,
        :func:`railradio.tunnel.modes.rect_modal_gain`) [dB/km] and ``modal_max_diff_db``
        (the largest |rays - modes| window mean at the highest order) [dB]; the variable
        ``modal_local_mean_db`` [centre_m] holds the modal window means.

    Raises
    ------
    ValueError
        When the configuration is invalid for the tunnel, cable or image method.
    """
    r = cfg["rays"]
    tun = tunnel_from_config(cfg, "rect")
    lam = cable_from_config(cfg).wavelength_m
    eps = eps_from_config(cfg)
    lb = beat_length_m(tun, lam)
    lo, hi = (float(v) for v in r["far_decay_m"])
    centres = np.arange(lo, hi + 1e-9, lb / 4.0)
    # samples 0.293 m apart (not commensurate with lambda/2) over every window
    x = np.arange(lo - lb / 2.0, hi + lb / 2.0, 0.293)
    cum = np.cumsum(coherent_gain_by_order(image_families(tun, r["max_order"]), x, lam, eps, "paraxial"), axis=0)
    p = np.abs(cum) ** 2
    lm_db = _window_means_db(x, p, centres, lb)
    slope = -np.polyfit(centres / 1e3, lm_db.T, 1)[0]  # [order] dB/km
    modal_db = _window_means_db(x, np.abs(rect_modal_gain(tun, x, lam, eps)) ** 2, centres, lb)
    modal_slope = -float(np.polyfit(centres / 1e3, modal_db, 1)[0])
    conv = np.all(np.abs(lm_db - lm_db[-1]) <= 0.1, axis=1)
    conv_order = int(np.argmax(conv))
    eh11 = eh11_attenuation_db_per_m(lam, tun.width_m, tun.height_m, eps) * 1e3
    return xr.Dataset(
        {
            "local_mean_db": (
                ("order", "centre_m"),
                lm_db,
                {
                    "units": "dB",
                    "long_name": (
                        "one slot's coherent power averaged over one beat length (unit EIRP), truncated at "
                        "each reflection order"
                    ),
                },
            ),
            "slope_db_per_km": (
                "order",
                slope,
                {"units": "dB/km", "long_name": "least-squares decay of local_mean_db over the centres"},
            ),
            "modal_local_mean_db": (
                "centre_m",
                modal_db,
                {
                    "units": "dB",
                    "long_name": "the same window means of the lossy EH_mn modal sum (railradio.tunnel.modes)",
                },
            ),
        },
        coords={
            "order": (
                "order",
                np.arange(lm_db.shape[0]),
                {"units": "1", "long_name": "highest reflection order summed"},
            ),
            "centre_m": ("centre_m", centres, {"units": "m", "long_name": "window centre (offset from the slot)"}),
        },
        attrs={
            "beat_length_m": lb,
            "eh11_db_per_km": eh11,
            "converged_order": conv_order,
            "slope_db_per_km": float(slope[-1]),
            "modal_slope_db_per_km": modal_slope,
            "modal_max_diff_db": float(np.max(np.abs(lm_db[-1] - modal_db))),
        },
    )


def modal_near_check(cfg: dict[str, Any], order: int, reach_m: float = 600.0, step_m: float = 0.04) -> dict[str, float]:
    """Where the square's modal sum stops being its field: one slot's local mean (the
    coherent power averaged over ``rays.local_mean_wavelengths``, consecutive windows from
    the slot to ``reach_m``) from the image method at ``order`` and from the lossy EH_mn
    modal sum (:func:`railradio.tunnel.modes.rect_modal_gain`), their largest difference in
    the first window and beyond it.  Near the slot the steep rays meet the lining far from
    grazing, where the modes' perturbative losses do not hold: rays are needed there.

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration (``geometry``, ``cable``, ``wall``,
        ``rays.local_mean_wavelengths``).
    order : int
        Reflection order of the image method (the table's).
    reach_m : float
        Offset up to which the windows run [m].
    step_m : float
        Offset sample spacing [m].

    Returns
    -------
    dict
        ``window_m`` (the local-mean window) [m], ``first_window_diff_db`` (|modes - rays| in
        the window at the slot) and ``beyond_max_diff_db`` (the largest |modes - rays| of the
        later windows) [dB].

    Raises
    ------
    ValueError
        When the configuration is invalid for the tunnel, cable or image method.
    """
    tun = tunnel_from_config(cfg, "rect")
    lam = cable_from_config(cfg).wavelength_m
    eps = eps_from_config(cfg)
    lw = local_mean_window(cfg)
    x = np.arange(0.0, reach_m, step_m) + step_m / 2.0
    rays = np.abs(coherent_gain_by_order(image_families(tun, order), x, lam, eps, "paraxial").sum(axis=0)) ** 2
    modes = np.abs(rect_modal_gain(tun, x, lam, eps)) ** 2
    win = np.floor(x / lw).astype(int)
    full = win < int(reach_m // lw)
    diff = np.abs(
        10 * np.log10(np.bincount(win[full], modes[full]) / np.bincount(win[full], rays[full]))
    )  # equal counts per window
    return {"window_m": lw, "first_window_diff_db": float(diff[0]), "beyond_max_diff_db": float(diff[1:].max())}


def far_decay_circle(cfg: dict[str, Any], sample_m: float = 0.293) -> xr.Dataset:
    """The circle's far field: one slot's local mean from the lossy modes of the circular
    guide (:func:`railradio.tunnel.modes.circle_modal_gain`, Marcatili & Schmeltzer 1964),
    averaged over windows of the circle's EH11-EH12 beat length centred every quarter beat
    length over ``rays.far_decay_m`` (as :func:`far_decay` in the square), its least-squares
    slope, against the single modes' attenuation (EH11, and TE01, the least attenuated of
    all); beside it the SBR engine's same statistic (the configured polarization rule, the
    reflection product interpolated in sin b as in the tables) and its largest difference
    from the modal one, the check that retired SBR in the circle (docs/model/tunnel.md §2.2).

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration (``geometry``, ``cable``, ``wall``,
        ``rays``; ``rays.far_decay_m`` [m], ``rays.max_order``, ``rays.sbr_rays``,
        ``rays.sbr_rx_radius_m`` [m], ``rays.sbr_polarization``).
    sample_m : float
        Spacing of the offset samples averaged in each window [m].

    Returns
    -------
    xarray.Dataset
        Over ``circle_centre_m`` (window centre, offset from the slot) [m]:
        ``circle_modal_local_mean_db`` and ``circle_sbr_local_mean_db`` (unit EIRP) [dB].
        Attributes ``beat_length_m`` [m], ``modal_slope_db_per_km``, ``sbr_slope_db_per_km``,
        ``eh11_db_per_km``, ``te01_db_per_km`` [dB/km], ``sbr_modal_max_diff_db`` (largest
        |SBR - modes| window mean) [dB], ``n_modes`` (modes summed), ``n_families`` (SBR ray
        families) [1].

    Raises
    ------
    ValueError
        When the configuration is invalid for the tunnel, cable or SBR engine.
    """
    r = cfg["rays"]
    tun = tunnel_from_config(cfg, "circle")
    lam = cable_from_config(cfg).wavelength_m
    eps = eps_from_config(cfg)
    lb = beat_length_m(tun, lam)
    lo, hi = (float(v) for v in r["far_decay_m"])
    centres = np.arange(lo, hi + 1e-9, lb / 4.0)
    x = np.arange(lo - lb / 2.0, hi + lb / 2.0, sample_m)
    fam = families(cfg, "circle", "sbr", r["max_order"])
    p_sbr = np.abs(coherent_gain_by_order(fam, x, lam, eps, r["sbr_polarization"]).sum(axis=0)) ** 2
    sbr_db = _window_means_db(x, p_sbr, centres, lb)
    modal_db = _window_means_db(x, np.abs(circle_modal_gain(tun, x, lam, eps)) ** 2, centres, lb)
    radius = tun.diameter_m / 2.0
    dims = ("circle_centre_m",)
    return xr.Dataset(
        {
            "circle_modal_local_mean_db": (
                dims,
                modal_db,
                {"units": "dB", "long_name": "one slot's local mean in the circle, lossy modal sum (beat windows)"},
            ),
            "circle_sbr_local_mean_db": (
                dims,
                sbr_db,
                {"units": "dB", "long_name": "the same window means of the SBR engine in the circle (retired)"},
            ),
        },
        coords={"circle_centre_m": (dims, centres, {"units": "m", "long_name": "window centre, offset from the slot"})},
        attrs={
            "beat_length_m": lb,
            "modal_slope_db_per_km": float(-np.polyfit(centres / 1e3, modal_db, 1)[0]),
            "sbr_slope_db_per_km": float(-np.polyfit(centres / 1e3, sbr_db, 1)[0]),
            "sbr_modal_max_diff_db": float(np.max(np.abs(sbr_db - modal_db))),
            "eh11_db_per_km": circular_attenuation_db_per_m(lam, radius, "EH11", eps) * 1e3,
            "te01_db_per_km": circular_attenuation_db_per_m(lam, radius, "TE01", eps) * 1e3,
            "n_modes": len(circle_modes(tun, lam, eps)["beta"]),
            "n_families": len(fam),
        },
    )


def cutoff_check(cfg: dict[str, Any], table: xr.Dataset, x_step_m: float = 2.0, step_m: float = 0.2) -> xr.Dataset:
    """Is the table long enough?  At receivers every ``x_step_m`` along the tunnel: the
    share of the local-mean power (summed over slots) from the slots beyond the table's
    extent c, and the RMS delay spread of the slots within c, within 2c and within c/2.
    A table covering the whole tunnel leaves no slot beyond it (share 0, the doubled
    cut-off adds nothing); a shorter one is compared with the channel tabulated to 2c (at
    the table's order, on a ``step_m`` grid: the local mean and the power delay profile are
    averages over 40 wavelengths, which a 0.2 m grid samples 66 times).

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration (``geometry``, ``cable``, ``wall``,
        ``rays``; ``rays.delay_bin_ns`` [ns], ``rays.n_delay_bins``,
        ``rays.local_mean_wavelengths``, ``rays.cutoff_power_frac`` [1]).
    table : xarray.Dataset
        The image-method table (:func:`railradio.tunnel.study.make_table` ``'image'``) with
        the attributes ``shape`` and ``reflection_order``; its extent c is its largest offset.
    x_step_m : float
        Spacing of the receiver positions along the tunnel [m].
    step_m : float
        Offset step of the channel tabulated to 2c [m]; it must divide the slot spacing.

    Returns
    -------
    xarray.Dataset
        Over ``x_m`` (receiver positions every ``x_step_m`` from the portal [m]):
        ``power_beyond_cutoff_frac`` [1], ``delay_rms_cutoff_s``, ``delay_rms_doubled_s``,
        ``delay_rms_halved_s`` (slots within c, 2c and c/2) [s].  Attributes ``cutoff_m``
        (the table's extent c) [m] and ``cutoff_power_frac`` [1].

    Raises
    ------
    ValueError
        When the table is shorter than the tunnel and ``step_m`` does not divide the slot
        spacing; when the configuration is invalid for the tunnel or cable.
    """
    r = cfg["rays"]
    tun = tunnel_from_config(cfg, table.attrs["shape"])
    cab = cable_from_config(cfg)
    off = table["offset_m"].values
    cut = float(off[-1])
    if cut >= tun.length_m - 1e-9:
        long = table
    else:
        long = tabulate(
            image_families(tun, table.attrs["reflection_order"]),
            tun,
            cab,
            offset_grid_m(step_m, min(2.0 * cut, tun.length_m), tun.slot_spacing_m),
            eps=eps_from_config(cfg),
            polarization="paraxial",
            delay_bin_s=r["delay_bin_ns"] * 1e-9,
            n_delay_bins=r["n_delay_bins"],
            local_mean_window_m=local_mean_window(cfg),
        )
    half = table.isel(offset_m=slice(0, int(np.searchsorted(off, cut / 2.0 + 1e-9))))
    x = np.arange(0.0, tun.length_m + 1e-9, x_step_m)
    a, c = received(table, tun, cab, x), received(half, tun, cab, x)
    b = a if long is table else received(long, tun, cab, x)
    share = 1.0 - 10.0 ** ((a.rssi_mean_dbm - b.rssi_mean_dbm) / 10.0)
    dims = ("x_m",)
    return xr.Dataset(
        {
            "power_beyond_cutoff_frac": (
                dims,
                share,
                {
                    "units": "1",
                    "long_name": "share of the local-mean power (sum over slots) from slots beyond the table's extent",
                },
            ),
            "delay_rms_cutoff_s": (
                dims,
                a.delay_rms_s,
                {"units": "s", "long_name": "RMS delay spread, slots within the table's extent"},
            ),
            "delay_rms_doubled_s": (
                dims,
                b.delay_rms_s,
                {"units": "s", "long_name": "RMS delay spread, slots within twice the table's extent"},
            ),
            "delay_rms_halved_s": (
                dims,
                c.delay_rms_s,
                {"units": "s", "long_name": "RMS delay spread, slots within half the table's extent"},
            ),
        },
        coords={"x_m": (dims, x, {"units": "m", "long_name": "receiver position along the tunnel"})},
        attrs={"cutoff_m": cut, "cutoff_power_frac": float(r["cutoff_power_frac"])},
    )


def make_engines(cfg: dict[str, Any], table: xr.Dataset) -> xr.Dataset:
    """Image method vs SBR in the rectangular tunnel (and SBR in the circle): per-slot
    local-mean and coherent gain at a set of offsets, same order, same Fresnel rule; the
    far decay checks (:func:`far_decay`, :func:`far_decay_circle`) and the cut-off check
    of the image-method ``table`` (:func:`cutoff_check`).

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration (``geometry``, ``cable``, ``wall``,
        ``rays``; ``rays.engine_offsets_m`` [m], ``rays.far_decay_m`` [m],
        ``rays.max_order``, ``rays.sbr_polarization``, ...).
    table : xarray.Dataset
        The image-method table (:func:`railradio.tunnel.study.make_table` ``'image'``); its
        ``reflection_order`` is used by every engine.

    Returns
    -------
    xarray.Dataset
        Over ``model`` (``image_rect``, ``sbr_rect``, ``sbr_rect_vector``)
        and ``offset_m`` [m]: ``power_mean_db`` (incoherent sum of one slot's ray powers,
        unit EIRP) [dB], ``power_coherent_db`` (coherent path gain) [dB], ``n_rays`` [model];
        over ``far_order`` and ``centre_m`` [m] (:func:`far_decay`): ``far_local_mean_db``
        [dB], ``far_slope_db_per_km`` [far_order] [dB/km]; over ``x_m`` [m]
        (:func:`cutoff_check`): ``power_beyond_cutoff_frac`` [1], ``delay_rms_cutoff_s``,
        ``delay_rms_doubled_s``, ``delay_rms_halved_s`` [s]; over ``circle_centre_m`` [m]
        (:func:`far_decay_circle`): ``circle_modal_local_mean_db``, ``circle_sbr_local_mean_db``
        [dB].  Attributes:
        ``reflection_order``, ``far_*`` (:func:`far_decay`), ``far_circle_*``
        (:func:`far_decay_circle`), ``modal_near_*`` (:func:`modal_near_check`), ``cutoff_m``
        [m], ``cutoff_power_frac`` [1].

    Raises
    ------
    ValueError
        When the configuration is invalid for the tunnel, cable or ray engines.
    """
    order = int(table.attrs["reflection_order"])
    cab = cable_from_config(cfg)
    eps = eps_from_config(cfg)
    offs = np.array(cfg["rays"]["engine_offsets_m"], dtype=float)
    out = {}
    for label, shape, engine, pol in (
        ("image_rect", "rect", "image", "paraxial"),
        ("sbr_rect", "rect", "sbr", "paraxial"),
        ("sbr_rect_vector", "rect", "sbr", "vector"),
    ):
        rays = lift(families(cfg, shape, engine, order), offs, cab.wavelength_m, eps, pol)
        out[label] = (
            10 * np.log10(np.sum(np.abs(rays.amplitude) ** 2, axis=0)),
            20 * np.log10(np.abs(rays.amplitude.sum(axis=0))),
            rays.amplitude.shape[0],
        )
    labels = list(out)
    far = far_decay(cfg)
    cut = cutoff_check(cfg, table)
    ds = xr.Dataset(
        {
            "power_mean_db": (
                ("model", "offset_m"),
                np.array([out[k][0] for k in labels]),
                {"units": "dB", "long_name": "incoherent sum of the rays' powers of one slot (unit EIRP)"},
            ),
            "power_coherent_db": (
                ("model", "offset_m"),
                np.array([out[k][1] for k in labels]),
                {"units": "dB", "long_name": "coherent path gain of one slot (unit EIRP)"},
            ),
            "n_rays": ("model", np.array([out[k][2] for k in labels]), {"units": "1", "long_name": "rays (families)"}),
        },
        coords={
            "model": ("model", labels, {"units": "1", "long_name": "engine, cross-section, polarization rule"}),
            "offset_m": ("offset_m", offs, {"units": "m", "long_name": "along-axis offset"}),
        },
        attrs={"reflection_order": order},
    )
    ds = ds.merge(
        far.rename({"order": "far_order"}).rename_vars(
            {"local_mean_db": "far_local_mean_db", "slope_db_per_km": "far_slope_db_per_km"}
        )
    )
    ds = ds.merge(cut)
    circ = far_decay_circle(cfg)
    ds = ds.merge(circ.drop_attrs(deep=False))
    near = modal_near_check(cfg, order)
    ds.attrs.update(
        {
            "reflection_order": order,
            **{f"far_{k}": v for k, v in far.attrs.items()},
            **{f"far_circle_{k}": v for k, v in circ.attrs.items()},
            **{f"modal_near_{k}": v for k, v in near.items()},
            "cutoff_m": cut.attrs["cutoff_m"],
            "cutoff_power_frac": cut.attrs["cutoff_power_frac"],
        }
    )
    return ds
