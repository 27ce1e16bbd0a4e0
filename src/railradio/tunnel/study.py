"""Config -> objects, and the pipeline steps of the tunnel study (kept out of the scripts)."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from railradio.rng import make_rng, spawn_key
from railradio.tunnel.channel import (
    SeedModel,
    beat_length_m,
    coherent_gain_by_order,
    lee_window_m,
    moving_mean,
    offset_grid_m,
    received,
    tabulate,
    window_samples,
)
from railradio.tunnel.geometry import Cable, Tunnel
from railradio.tunnel.rays import Families, image_families, lift, sbr_families
from railradio.tunnel.simulate import MeasurementModel, Train

TABLES = {
    "image": ("rect", "image", "physical"),
    "sbr": ("circle", "sbr", "physical"),
    "seed": ("rect", "image", "seed"),
    "image_side_wall": ("rect", "image", "physical"),
    "sbr_side_wall": ("circle", "sbr", "physical"),
}
"""table name -> (cross-section, engine, propagation); ``*_side_wall``: the same engine with the
cable at ``sensitivity.side_wall_slot_z_m`` (:func:`side_wall_config`)."""
SIDE_WALL = "_side_wall"


def channel_config(cfg: dict[str, Any], name: str, keys: list[str]) -> dict[str, Any]:
    """The sections ``keys`` of the tunnel config for table ``name`` (side-wall tables: the
    slot line moved, :func:`side_wall_config`); the other tables' config stays unchanged."""
    c = side_wall_config(cfg) if SIDE_WALL in name else cfg
    return {k: c[k] for k in keys}


def side_wall_config(cfg: dict[str, Any]) -> dict[str, Any]:
    """The tunnel config with the slot line moved to the side wall (the sensitivity variant)."""
    z = cfg["sensitivity"]["side_wall_slot_z_m"]
    return cfg | {"geometry": cfg["geometry"] | {"slot_z_m": z}}


VARIANTS = {
    "physical_separable": ("physical", "separable"),
    "physical_separable_ar1": ("physical", "separable"),
    "physical_separable_slot_bias": ("physical", "separable"),
    "physical_wideband": ("physical", "wideband"),
    "seed_separable": ("seed", "separable"),
}
VARIANT_DELAY_ERROR = {"physical_separable_ar1": "ar1", "physical_separable_slot_bias": "slot_bias"}
"""Runs of the separable receiver with a correlated delay error instead of the configured
one (white, the source's reading [ours]); the same draws otherwise."""
TABLE_OF_PROPAGATION = {"physical": None, "seed": "seed"}  # physical: the configured engine


def tunnel_from_config(cfg: dict[str, Any], shape: str = "circle") -> Tunnel:
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
    return complex(cfg["wall"]["eps_real"], -cfg["wall"]["eps_imag"])


def measurement_from_config(cfg: dict[str, Any], **overrides: Any) -> MeasurementModel:
    """The measurement model of ``cfg['measurement']``, with keys of that section overridden."""
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


def _label(v: float) -> str:
    return f"{v:g}".replace(".", "p").replace("-", "m")


def sensitivity_cases(cfg: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Sensitivity cases (shadowing and delay-error sigma swept over the seed's
    ranges; the delay-error model): label -> overrides of the measurement section, each
    case changing one thing from the defaults, and the delay-sigma sweep repeated with each
    correlated delay-error model (``delay_sigma_ns_<v>_<model>``)."""
    sv = cfg["sensitivity"]
    cases: dict[str, dict[str, Any]] = {}
    for v in sv["shadow_sigma_db"]:
        cases[f"shadow_sigma_db_{_label(v)}"] = {"shadow_sigma_db": float(v)}
    for v in sv["delay_sigma_ns"]:
        cases[f"delay_sigma_ns_{_label(v)}"] = {"delay_sigma_ns": float(v)}
    for e in sv["delay_errors"]:
        cases[f"delay_error_{e}"] = {"delay_error": e}
    for e in sv["delay_errors"]:  # the delay-sigma sweep with each correlated error model
        if e != "white":
            for v in sv["delay_sigma_ns"]:
                cases[f"delay_sigma_ns_{_label(v)}_{e}"] = {"delay_sigma_ns": float(v), "delay_error": e}
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
    measurements, that geometry and channel."""
    from railradio.tunnel.simulate import calibrate_separable, kf_realizations

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


PEAK_BIAS_CASES = ("single_slot", "los_slots", "full", "full_all_slots")
"""Noiseless wideband peak-delay offsets: the nearest slot's line-of-sight ray alone; every
slot's line-of-sight ray in the receiver's window (absorbing walls); the full channel in the
window (the receiver's model); the full channel of every tabulated slot."""


def make_peak_bias(cfg: dict[str, Any], table: xr.Dataset, step_m: float = 9.7) -> xr.Dataset:
    """Where the wideband receiver's peak-delay bias comes from: the noiseless CIR-peak delay
    minus the cable-point model delay (cable delay to x + h/c) at receivers every ``step_m``
    along the tunnel (not a divisor of the slot spacing: every offset to the nearest slot
    occurs), for the cases of :data:`PEAK_BIAS_CASES` (same estimator, same
    bandwidth and tones; the line-of-sight table has absorbing walls)."""
    import dataclasses

    from railradio.tunnel.channel import tabulate
    from railradio.tunnel.simulate import cable_model_delay_s, tone_response, wideband_delays

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


def train_from_config(cfg: dict[str, Any], name: str) -> Train:
    t = cfg["trains"][name]
    return Train(name, t["length_m"], t["speed_kmh"], cfg["positioning"]["n_receivers"])


def families(cfg: dict[str, Any], shape: str, engine: str, order: int) -> Families:
    tun = tunnel_from_config(cfg, shape)
    if engine == "image":
        return image_families(tun, order)
    r = cfg["rays"]
    return sbr_families(tun, r["sbr_rays"], order, r["sbr_rx_radius_m"])


def local_mean_window(cfg: dict[str, Any]) -> float:
    """The local-mean window [m] of ``rays.local_mean_wavelengths`` wavelengths."""
    return lee_window_m(cable_from_config(cfg).wavelength_m, cfg["rays"]["local_mean_wavelengths"])


def table_extent_m(cfg: dict[str, Any], propagation: str = "physical") -> float:
    """The largest slot-receiver offset the table holds [m]: ``rays.max_offset_m``, or with
    it null the whole tunnel (every slot a receiver in the tunnel can see); the seed's model
    ``seed_model.max_offset_m`` (its own attenuation leaves nothing beyond it)."""
    length = float(cfg["geometry"]["length_m"])
    m = cfg["seed_model"]["max_offset_m"] if propagation == "seed" else cfg["rays"]["max_offset_m"]
    return length if m is None else min(float(m), length)


def choose_order(cfg: dict[str, Any]) -> tuple[int, np.ndarray, np.ndarray]:
    """Reflection order by convergence of the coherent gain (the narrowband field the
    positioning measures) in the image-method tunnel: the smallest order N whose omitted
    orders N+1..``max_order`` carry a field at most ``convergence_field_db`` below the
    local mean at every offset from 0 to the table's extent (:func:`table_extent_m`) on a
    ``convergence_step_m`` grid.  Returns (order, the worst omitted field over offsets
    [dB re local mean] per order, the offsets)."""
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
    window means are within 0.1 dB of it tells whether it converged."""
    from railradio.tunnel.materials import eh11_attenuation_db_per_m

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
        },
    )


def far_decay_circle(cfg: dict[str, Any], sample_m: float = 1.0) -> dict[str, float]:
    """The circular engine (SBR, the configured polarization rule) checked far from the slot
    against an independent reference: one slot's local mean averaged over windows of the
    square's beat length (as :func:`far_decay`; samples ``sample_m`` apart), its slope over
    ``rays.far_decay_m`` at ``max_order`` (the reflection product interpolated in sin b as
    in the tables), against Marcatili & Schmeltzer's attenuation of
    EH11 and TE01 in a lossy circular guide of the tunnel's radius (TE01, the least
    attenuated mode, bounds every mode's decay from below)."""
    from railradio.tunnel.materials import circular_attenuation_db_per_m

    r = cfg["rays"]
    tun = tunnel_from_config(cfg, "circle")
    lam = cable_from_config(cfg).wavelength_m
    eps = eps_from_config(cfg)
    lb = beat_length_m(tunnel_from_config(cfg, "rect"), lam)
    lo, hi = (float(v) for v in r["far_decay_m"])
    centres = np.arange(lo, hi + 1e-9, lb / 4.0)
    x = np.arange(lo - lb / 2.0, hi + lb / 2.0, sample_m)
    fam = families(cfg, "circle", "sbr", r["max_order"])
    p = np.abs(coherent_gain_by_order(fam, x, lam, eps, r["sbr_polarization"]).sum(axis=0)) ** 2
    lm_db = _window_means_db(x, p, centres, lb)
    radius = tun.diameter_m / 2.0
    return {
        "slope_db_per_km": float(-np.polyfit(centres / 1e3, lm_db, 1)[0]),
        "eh11_db_per_km": circular_attenuation_db_per_m(lam, radius, "EH11", eps) * 1e3,
        "te01_db_per_km": circular_attenuation_db_per_m(lam, radius, "TE01", eps) * 1e3,
        "n_families": len(fam),
    }


def cutoff_check(cfg: dict[str, Any], table: xr.Dataset, x_step_m: float = 2.0, step_m: float = 0.2) -> xr.Dataset:
    """Is the table long enough?  At receivers every ``x_step_m`` along the tunnel: the
    share of the local-mean power (summed over slots) from the slots beyond the table's
    extent c, and the RMS delay spread of the slots within c, within 2c and within c/2.
    A table covering the whole tunnel leaves no slot beyond it (share 0, the doubled
    cut-off adds nothing); a shorter one is compared with the channel tabulated to 2c (at
    the table's order, on a ``step_m`` grid: the local mean and the power delay profile are
    averages over 40 wavelengths, which a 0.2 m grid samples 66 times)."""
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


def make_order(cfg: dict[str, Any]) -> xr.Dataset:
    """The reflection order of :func:`choose_order` with the worst omitted field per order
    (one file per cable placement, read by every table of that placement)."""
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
    reflection order of ``order`` (:func:`make_order` for the table's cable placement)."""
    shape, engine, prop = TABLES[name]
    omitted = order["omitted_field_db"]
    order = int(order.attrs["reflection_order"])
    fam = families(cfg, shape, engine, order)
    tun = tunnel_from_config(cfg, shape)
    cab = cable_from_config(cfg)
    r = cfg["rays"]
    sm = cfg["seed_model"]
    grid = offset_grid_m(r["offset_step_m"], table_extent_m(cfg, prop), tun.slot_spacing_m)
    pol = "paraxial" if engine == "image" else cfg["rays"]["sbr_polarization"]
    rng = make_rng(seed, spawn_key("tunnel", 10)) if prop == "seed" else None
    ds = tabulate(
        fam,
        tun,
        cab,
        grid,
        eps=eps_from_config(cfg),
        polarization=pol,
        propagation=prop,
        seed_model=SeedModel(sm["reflection_loss_db"], sm["tunnel_att_db_per_m"], sm["multipath_max_db"]),
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
    """RSSI (coherent, local mean), RMS delay spread, strong-ray count along the tunnel."""
    shape = TABLES[name][0]
    tun = tunnel_from_config(cfg, shape)
    cab = cable_from_config(cfg)
    step = cfg["coverage"]["map_step_m"]
    x = np.arange(int(round(tun.length_m / step)) + 1) * step
    rec = received(table, tun, cab, x, strong_dbm=cfg["coverage"]["blind_spot_dbm"])
    lm_name = "RSSI, local mean (power sum over rays, seed 2.4.3)"
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
                    "long_name": "RMS delay spread of the local-mean power delay profile of all slots (seed 2.5.2)",
                },
            ),
            "n_strong_rays": (dims, rec.n_strong_rays, {"units": "1", "long_name": "rays above the blind-spot level"}),
        },
        coords={"x_m": (dims, x, {"units": "m", "long_name": "receiver position along the tunnel"})},
        attrs={"table": name, "shape": shape, "cross_distance_m": tun.cross_distance_m},
    )


def make_engines(cfg: dict[str, Any], table: xr.Dataset) -> xr.Dataset:
    """Image method vs SBR in the rectangular tunnel (and SBR in the circle): per-slot
    local-mean and coherent gain at a set of offsets, same order, same Fresnel rule; the
    far decay checks (:func:`far_decay`, :func:`far_decay_circle`) and the cut-off check
    of the image-method ``table`` (:func:`cutoff_check`)."""
    order = int(table.attrs["reflection_order"])
    cab = cable_from_config(cfg)
    eps = eps_from_config(cfg)
    offs = np.array(cfg["rays"]["engine_offsets_m"], dtype=float)
    out = {}
    for label, shape, engine, pol in (
        ("image_rect", "rect", "image", "paraxial"),
        ("sbr_rect", "rect", "sbr", "paraxial"),
        ("sbr_rect_vector", "rect", "sbr", "vector"),
        ("sbr_circle", "circle", "sbr", cfg["rays"]["sbr_polarization"]),
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
    ds.attrs.update(
        {
            "reflection_order": order,
            **{f"far_{k}": v for k, v in far.attrs.items()},
            **{f"far_circle_{k}": v for k, v in circ.items()},
            "cutoff_m": cut.attrs["cutoff_m"],
            "cutoff_power_frac": cut.attrs["cutoff_power_frac"],
        }
    )
    return ds
