"""Config -> objects, and the channel steps of the tunnel study: the reflection order, the
slot-to-receiver tables, the maps along the tunnel (kept out of the scripts)."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import xarray as xr

from railradio.rng import make_rng, spawn_key
from railradio.tunnel.channel import (
    SourceModel,
    coherent_gain_by_order,
    lee_window_m,
    moving_mean,
    offset_grid_m,
    received,
    tabulate,
    window_samples,
)
from railradio.tunnel.delay_profile import delay_spread_note, received_spreads
from railradio.tunnel.geometry import Cable, Tunnel
from railradio.tunnel.measurement import MeasurementModel
from railradio.tunnel.rays import Families, image_families, sbr_families
from railradio.tunnel.simulate import Train
from railradio.tunnel.wideband_runs import CableModelError

TABLES = {
    "image": ("rect", "image", "physical"),
    "source": ("rect", "image", "source"),
    "image_side_wall": ("rect", "image", "physical"),
}
"""table name -> (cross-section, engine, propagation); ``*_side_wall``: the same engine with the
cable at ``sensitivity.side_wall_slot_z_m`` (:func:`side_wall_config`)."""
SIDE_WALL = "_side_wall"
"""Suffix of the table names whose cable runs on the side wall (:data:`TABLES`, :func:`channel_config`)."""


def channel_config(cfg: dict[str, Any], name: str, keys: list[str]) -> dict[str, Any]:
    """The sections ``keys`` of the tunnel config for table ``name`` (side-wall tables: the
    slot line moved, :func:`side_wall_config`); the other tables' config stays unchanged.

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration.
    name : str
        Table name (a key of :data:`TABLES`); a name containing :data:`SIDE_WALL` takes the
        side-wall slot line.
    keys : list of str
        Sections of ``cfg`` to keep (e.g. ``geometry``, ``cable``, ``wall``, ``rays``).

    Returns
    -------
    dict
        Section name -> section, for the sections ``keys``.
    """
    c = side_wall_config(cfg) if SIDE_WALL in name else cfg
    return {k: c[k] for k in keys}


def side_wall_config(cfg: dict[str, Any]) -> dict[str, Any]:
    """The tunnel config with the slot line moved to the side wall (the sensitivity case).

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration; ``sensitivity.side_wall_slot_z_m`` holds
        the transverse position of the slot line on the side wall [m].

    Returns
    -------
    dict
        A new config with ``geometry.slot_z_m`` replaced (``cfg`` is not modified; the other
        sections are shared with it).
    """
    z = cfg["sensitivity"]["side_wall_slot_z_m"]
    return cfg | {"geometry": cfg["geometry"] | {"slot_z_m": z}}


SETUPS = {
    "physical_separable": ("physical", "separable"),
    "physical_separable_ar1": ("physical", "separable"),
    "physical_separable_slot_bias": ("physical", "separable"),
    "physical_wideband": ("physical", "wideband"),
    "physical_wideband_slow": ("physical", "wideband"),
    "physical_wideband_vf": ("physical", "wideband"),
    "physical_wideband_feed": ("physical", "wideband"),
    "source_separable": ("source", "separable"),
}
"""Run setup -> (propagation of the channel table, measurement model of the receiver)."""
SETUP_SLOW = ("physical_wideband_slow",)
"""Runs at ``cases.low_speed_kmh`` instead of the train's cruise speed; the same draws otherwise."""
SETUP_CABLE_ERROR = {"physical_wideband_vf": "velocity_factor", "physical_wideband_feed": "feed_delay"}
"""Wideband runs whose cable model is wrong by one stated installation error (``cases``)."""
SETUP_DELAY_ERROR = {"physical_separable_ar1": "ar1", "physical_separable_slot_bias": "slot_bias"}
"""Runs of the separable receiver with a correlated delay error instead of the configured
one (white, the source's reading [ours]); the same draws otherwise."""
TABLE_OF_PROPAGATION = {"physical": None, "source": "source"}  # physical: the configured engine


def tunnel_from_config(cfg: dict[str, Any], shape: str = "circle") -> Tunnel:
    """The tunnel of ``cfg['geometry']`` with cross-section ``shape``.

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration; ``geometry`` holds ``length_m``,
        ``diameter_m``, ``slot_spacing_m``, ``rx_y_m``, ``rx_z_m``, ``slot_z_m`` [m] and
        ``slot_height_frac`` [1].
    shape : {'circle', 'rect'}
        Cross-section: the true circle, or the square of equal area (image method).

    Returns
    -------
    Tunnel
        The tunnel.

    Raises
    ------
    ValueError
        When the geometry is invalid (see :class:`~railradio.tunnel.geometry.Tunnel`).
    """
    g = cfg["geometry"]
    return Tunnel(
        g["length_m"],
        g["diameter_m"],
        shape,
        g["slot_spacing_m"],
        g["slot_height_frac"],
        g["slot_z_m"],
        g["rx_y_m"],
        g["rx_z_m"],
    )


def cable_from_config(cfg: dict[str, Any]) -> Cable:
    """The leaky cable of ``cfg['cable']``.

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration; ``cable`` holds ``frequency_hz`` [Hz],
        ``feed_power_dbm`` [dBm], ``feed_spacing_m`` [m], ``loss_db_per_100m`` [dB/100 m],
        ``velocity_factor`` [1], ``coupling_loss_db`` [dB], ``coupling_ref_m`` [m] and
        ``coupling_ref_gain_dbi`` [dBi].

    Returns
    -------
    Cable
        The cable (its loss converted to dB/m).

    Raises
    ------
    ValueError
        When the cable parameters are invalid (see :class:`~railradio.tunnel.geometry.Cable`).
    """
    c = cfg["cable"]
    return Cable(
        c["frequency_hz"],
        c["feed_power_dbm"],
        c["feed_spacing_m"],
        c["loss_db_per_100m"] / 100.0,
        c["velocity_factor"],
        c["coupling_loss_db"],
        c["coupling_ref_m"],
        c["coupling_ref_gain_dbi"],
    )


def eps_from_config(cfg: dict[str, Any]) -> complex:
    """The wall's relative permittivity eps_real - j eps_imag of ``cfg['wall']``.

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration; ``wall`` holds ``eps_real`` and
        ``eps_imag`` (the loss, given as a positive number) [1].

    Returns
    -------
    complex
        Relative permittivity [1] in the exp(+j omega t) convention (imaginary part <= 0).
    """
    return complex(cfg["wall"]["eps_real"], -cfg["wall"]["eps_imag"])


def measurement_from_config(cfg: dict[str, Any], **overrides: Any) -> MeasurementModel:
    """The measurement model of ``cfg['measurement']``, with keys of that section overridden.

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration; ``measurement`` holds
        ``shadow_sigma_db`` [dB], ``shadow_corr_m`` [m], ``delay_sigma_ns`` [ns],
        ``n_slots``, ``window_m`` [m], ``bandwidth_hz`` [Hz], ``n_tones``,
        ``noise_figure_db`` [dB], ``delay_error`` and ``delay_corr_m`` [m].
    **overrides
        Keys of the ``measurement`` section replaced (e.g. ``delay_error='ar1'``,
        ``delay_sigma_ns=35.0``), in that section's units.

    Returns
    -------
    MeasurementModel
        The measurement model (the delay sigma converted to s).

    Raises
    ------
    ValueError
        When the model is invalid (see :class:`~railradio.tunnel.measurement.MeasurementModel`).
    """
    m = cfg["measurement"] | overrides
    return MeasurementModel(
        m["shadow_sigma_db"],
        m["shadow_corr_m"],
        m["delay_sigma_ns"] * 1e-9,
        m["n_slots"],
        m["window_m"],
        m["bandwidth_hz"],
        m["n_tones"],
        m["noise_figure_db"],
        m["delay_error"],
        m["delay_corr_m"],
    )


def train_from_config(cfg: dict[str, Any], name: str) -> Train:
    """The train type ``name`` of ``cfg['trains']`` with ``positioning.n_receivers`` receivers.

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration; ``trains[name]`` holds ``length_m`` [m]
        and ``speed_kmh`` [km/h].
    name : str
        Train type (``metro``, ``hst``, ``freight``).

    Returns
    -------
    Train
        The train.

    Raises
    ------
    ValueError
        When the train is invalid (see :class:`~railradio.tunnel.simulate.Train`).
    """
    t = cfg["trains"][name]
    return Train(name, t["length_m"], t["speed_kmh"], cfg["positioning"]["n_receivers"])


def run_setup(cfg: dict[str, Any], name: str, setup: str) -> tuple[Train, CableModelError | None]:
    """The train and the receiver's cable-model error of run ``setup`` (:data:`SETUPS`).

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration; ``cases`` holds ``low_speed_kmh``
        [km/h], ``velocity_factor_rel`` [1] and ``feed_delay_max_ns`` [ns].
    name : str
        Train type (``metro``, ``hst``, ``freight``).
    setup : str
        Run setup, a key of :data:`SETUPS`.

    Returns
    -------
    tuple
        ``(train, cable_error)``: the train (at the low speed for :data:`SETUP_SLOW`), the
        :class:`~railradio.tunnel.wideband_runs.CableModelError` of :data:`SETUP_CABLE_ERROR` or None.

    Raises
    ------
    ValueError
        When ``setup`` is not a key of :data:`SETUPS`.
    """
    if setup not in SETUPS:
        raise ValueError(f"setup must be one of {sorted(SETUPS)}, got {setup!r}")
    train = train_from_config(cfg, name)
    cases = cfg["cases"]
    if setup in SETUP_SLOW:
        train = dataclasses.replace(train, speed_kmh=cases["low_speed_kmh"])
    err = SETUP_CABLE_ERROR.get(setup)
    if err == "velocity_factor":
        return train, CableModelError(velocity_factor_rel=cases["velocity_factor_rel"])
    if err == "feed_delay":
        return train, CableModelError(feed_delay_max_s=cases["feed_delay_max_ns"] * 1e-9)
    return train, None


def families(cfg: dict[str, Any], shape: str, engine: str, order: int) -> Families:
    """The 2-D ray families from the slot to the receiver in the tunnel of ``cfg`` by one engine.

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration (``geometry``; for SBR ``rays.sbr_rays``
        and ``rays.sbr_rx_radius_m`` [m]).
    shape : {'circle', 'rect'}
        Cross-section (:func:`tunnel_from_config`).
    engine : {'image', 'sbr'}
        'image': the image method (needs ``shape`` 'rect'); any other value: SBR.
    order : int
        Largest reflection order (image: |m| + |n|; SBR: reflections traced) [1].

    Returns
    -------
    Families
        The families (:func:`~railradio.tunnel.rays.image_families` or
        :func:`~railradio.tunnel.rays.sbr_families`).

    Raises
    ------
    ValueError
        When the geometry is invalid or the engine rejects the shape, order or SBR settings.
    """
    tun = tunnel_from_config(cfg, shape)
    if engine == "image":
        return image_families(tun, order)
    r = cfg["rays"]
    return sbr_families(tun, r["sbr_rays"], order, r["sbr_rx_radius_m"])


def local_mean_window(cfg: dict[str, Any]) -> float:
    """The local-mean window [m] of ``rays.local_mean_wavelengths`` wavelengths.

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration; ``cable`` (its frequency gives the
        wavelength) and ``rays.local_mean_wavelengths`` [1].

    Returns
    -------
    float
        Length of the local-mean window [m].

    Raises
    ------
    ValueError
        When the cable is invalid or ``rays.local_mean_wavelengths`` is not positive.
    """
    return lee_window_m(cable_from_config(cfg).wavelength_m, cfg["rays"]["local_mean_wavelengths"])


def table_extent_m(cfg: dict[str, Any], propagation: str = "physical") -> float:
    """The largest slot-receiver offset the table holds [m]: ``rays.max_offset_m``, or with
    it null the whole tunnel (every slot a receiver in the tunnel can see); the source's model
    ``source_model.max_offset_m`` (its own attenuation leaves nothing beyond it).

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration; ``geometry.length_m``,
        ``rays.max_offset_m`` and ``source_model.max_offset_m`` [m] (null: the tunnel length).
    propagation : {'physical', 'source'}
        'source': the source model's table; any other value: the ray tables.

    Returns
    -------
    float
        The table's extent [m], at most the tunnel length.
    """
    length = float(cfg["geometry"]["length_m"])
    m = cfg["source_model"]["max_offset_m"] if propagation == "source" else cfg["rays"]["max_offset_m"]
    return length if m is None else min(float(m), length)


def choose_order(cfg: dict[str, Any]) -> tuple[int, np.ndarray, np.ndarray]:
    """Reflection order by convergence of the coherent gain (the narrowband field the
    positioning measures) in the image-method tunnel: the smallest order N whose omitted
    orders N+1..``max_order`` carry a field at most ``convergence_field_db`` below the
    local mean at every offset from 0 to the table's extent (:func:`table_extent_m`) on a
    ``convergence_step_m`` grid.  Returns (order, the worst omitted field over offsets
    [dB re local mean] per order, the offsets).

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration (``geometry``, ``cable``, ``wall``,
        ``rays``; ``rays.max_order``, ``rays.convergence_field_db`` [dB],
        ``rays.convergence_step_m`` [m], ``rays.local_mean_wavelengths``, ``rays.max_offset_m`` [m]).

    Returns
    -------
    tuple
        ``(order, worst_db, offsets)``: the chosen order (int); per truncation order, the
        worst field of the orders it omits over the offsets, relative to the local mean
        [order] [dB]; the offsets [offset] [m].

    Raises
    ------
    ValueError
        When no order below ``rays.max_order`` converges, or the configuration is invalid
        for the tunnel or cable.
    """
    r = cfg["rays"]
    tun = tunnel_from_config(cfg, "rect")
    lam = cable_from_config(cfg).wavelength_m
    fam = image_families(tun, r["max_order"])
    step = r["convergence_step_m"]
    offs = np.arange(int(np.floor(table_extent_m(cfg) / step + 1e-9)) + 1) * step
    by_order = coherent_gain_by_order(fam, offs, lam, eps_from_config(cfg), "paraxial")
    cum = np.cumsum(by_order, axis=0)
    full = cum[-1]
    lm = moving_mean(np.abs(full) ** 2, window_samples(local_mean_window(cfg), step), mirror_start=True)
    worst_db = 10.0 * np.log10(np.max(np.abs(cum - full[None, :]) ** 2 / lm[None, :], axis=1) + 1e-300)
    ok = worst_db <= r["convergence_field_db"]
    ok[-1] = True
    order = int(np.argmax(ok))
    if order == r["max_order"]:
        raise ValueError(
            f"tunnel.rays.max_order={r['max_order']}: the coherent gain does not converge to "
            f"{r['convergence_field_db']} dB below the local mean; raise it"
        )
    return order, worst_db, offs


def make_order(cfg: dict[str, Any]) -> xr.Dataset:
    """The reflection order of :func:`choose_order` with the worst omitted field per order
    (one file per cable placement, read by every table of that placement).

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration (``geometry``, ``cable``, ``wall``,
        ``rays``; ``rays.max_order``, ``rays.convergence_field_db`` [dB],
        ``rays.convergence_step_m`` [m]).

    Returns
    -------
    xarray.Dataset
        ``omitted_field_db`` [order]: the worst field of the omitted higher orders over the
        table's offsets relative to the local mean [dB], ``order`` being the highest
        reflection order summed.  Attributes: ``reflection_order`` (the chosen order),
        ``max_offset_m`` [m], ``convergence_field_db`` [dB].

    Raises
    ------
    ValueError
        When the coherent gain has not converged by ``rays.max_order``.
    """
    order, worst_db, offs = choose_order(cfg)
    return xr.Dataset(
        {
            "omitted_field_db": (
                "order",
                worst_db,
                {
                    "units": "dB",
                    "long_name": "image method: worst field of the "
                    "omitted higher orders over the table's offsets, relative to the local mean",
                },
            )
        },
        coords={
            "order": ("order", np.arange(worst_db.size), {"units": "1", "long_name": "highest reflection order summed"})
        },
        attrs={
            "reflection_order": order,
            "max_offset_m": float(offs[-1]),
            "convergence_field_db": float(cfg["rays"]["convergence_field_db"]),
        },
    )


def make_table(cfg: dict[str, Any], name: str, seed: int, order: xr.Dataset) -> xr.Dataset:
    """The tabulated slot-to-receiver channel ``name`` (see :data:`TABLES`) at the
    reflection order of ``order`` (:func:`make_order` for the table's cable placement).

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration (``geometry``, ``cable``, ``wall``,
        ``rays``, ``source_model``); side-wall tables: the config of :func:`channel_config`.
    name : str
        Table name, a key of :data:`TABLES` (cross-section, engine, propagation).
    seed : int
        Root seed of the workflow (draws the source model's multipath losses only).
    order : xarray.Dataset
        The reflection order of :func:`make_order` (``reflection_order`` attribute,
        ``omitted_field_db``).

    Returns
    -------
    xarray.Dataset
        The table of :func:`~railradio.tunnel.channel.tabulate` (``taps``, ``power_mean``,
        ``power_incoherent``, ``delay_mean_s``, ``delay_rms_s``, ``los_delay_s`` over
        ``offset_m`` [m] and ``excess_delay_s`` [s]) with ``omitted_field_db`` [order] [dB]
        and the attributes ``reflection_order``, ``slot_eirp_offset_db`` (slot EIRP relative
        to the cable power [dB]) and the engine's statistics prefixed ``sbr_``.

    Raises
    ------
    ValueError
        When the configuration is invalid for the tunnel, cable, ray engine or table.
    """
    shape, engine, prop = TABLES[name]
    omitted = order["omitted_field_db"]
    order = int(order.attrs["reflection_order"])
    fam = families(cfg, shape, engine, order)
    tun = tunnel_from_config(cfg, shape)
    cab = cable_from_config(cfg)
    r = cfg["rays"]
    sm = cfg["source_model"]
    grid = offset_grid_m(r["offset_step_m"], table_extent_m(cfg, prop), tun.slot_spacing_m)
    pol = "paraxial" if engine == "image" else cfg["rays"]["sbr_polarization"]
    rng = make_rng(seed, spawn_key("tunnel", 10)) if prop == "source" else None
    ds = tabulate(
        fam,
        tun,
        cab,
        grid,
        eps=eps_from_config(cfg),
        polarization=pol,
        propagation=prop,
        source_model=SourceModel(sm["reflection_loss_db"], sm["tunnel_att_db_per_m"], sm["multipath_max_db"]),
        rng=rng,
        delay_bin_s=r["delay_bin_ns"] * 1e-9,
        n_delay_bins=r["n_delay_bins"],
        local_mean_window_m=local_mean_window(cfg) if prop == "physical" else None,
    )
    ds["omitted_field_db"] = omitted
    ds.attrs.update(
        {
            "reflection_order": order,
            "slot_eirp_offset_db": cab.slot_eirp_offset_db(tun.slot_spacing_m),
            **{f"sbr_{k}": v for k, v in fam.stats.items()},
        }
    )
    return ds


def make_map(cfg: dict[str, Any], table: xr.Dataset, name: str) -> xr.Dataset:
    """RSSI (coherent, local mean), RMS delay spread, strong-ray count along the tunnel.

    Parameters
    ----------
    cfg : dict
        The ``tunnel`` section of the configuration (``geometry``, ``cable`` and
        ``coverage``: ``map_step_m`` [m], ``blind_spot_dbm`` [dBm], the level of a strong ray).
    table : xarray.Dataset
        The tabulated channel ``name`` (:func:`make_table`).
    name : str
        Table name, a key of :data:`TABLES` (its cross-section).

    Returns
    -------
    xarray.Dataset
        Over ``x_m`` (receiver position along the tunnel, every ``map_step_m`` [m]):
        ``rssi_coherent_dbm`` [dBm], ``rssi_mean_dbm`` (local mean; physical: the coherent
        power averaged over the table's local-mean window) [dBm], ``delay_rms_s`` [s],
        ``n_strong_rays`` [1], ``delay_rms_thr<T>_s`` (the RMS delay spread with bins more
        than T dB below the profile's peak dropped, for every T of
        ``coverage.delay_spread_thresholds_db``) [s].  Attributes: ``table``, ``shape``, ``cross_distance_m`` [m].
    """
    shape = TABLES[name][0]
    tun = tunnel_from_config(cfg, shape)
    cab = cable_from_config(cfg)
    step = cfg["coverage"]["map_step_m"]
    x = np.arange(int(round(tun.length_m / step)) + 1) * step
    rec = received(table, tun, cab, x, strong_dbm=cfg["coverage"]["blind_spot_dbm"])
    spreads = received_spreads(table, tun, cab, x, tuple(cfg["coverage"]["delay_spread_thresholds_db"]))
    lm_name = "RSSI, local mean (power sum over rays, source 2.4.3)"
    if table.attrs["propagation"] == "physical":  # what a receiver measures: the coherent field's power averaged
        w = table.attrs["local_mean_window_m"]
        rec.rssi_mean_dbm = 10.0 * np.log10(
            moving_mean(10.0 ** (rec.rssi_coherent_dbm / 10.0), window_samples(w, step))
        )
        lm_name = f"RSSI, local mean (power of the coherent sum of all slots averaged over {w:.3g} m)"
    dims = ("x_m",)
    return xr.Dataset(
        {
            "rssi_coherent_dbm": (
                dims,
                rec.rssi_coherent_dbm,
                {"units": "dBm", "long_name": "RSSI, coherent sum of all rays of all slots"},
            ),
            "rssi_mean_dbm": (dims, rec.rssi_mean_dbm, {"units": "dBm", "long_name": lm_name}),
            "delay_rms_s": (
                dims,
                rec.delay_rms_s,
                {
                    "units": "s",
                    "long_name": "RMS delay spread of the local-mean power delay profile of all slots (source 2.5.2)",
                },
            ),
            "n_strong_rays": (dims, rec.n_strong_rays, {"units": "1", "long_name": "rays above the blind-spot level"}),
            **{
                f"delay_rms_thr{thr:g}_s": (dims, v, {"units": "s", "long_name": delay_spread_note(thr)})
                for thr, v in spreads.items()
                if thr is not None
            },
        },
        coords={"x_m": (dims, x, {"units": "m", "long_name": "receiver position along the tunnel"})},
        attrs={"table": name, "shape": shape, "cross_distance_m": tun.cross_distance_m},
    )
