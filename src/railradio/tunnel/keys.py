"""Key numbers of the tunnel study (docs/model/tunnel.md; source values from seed 003 §8)."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from railradio.keynumbers import KeySpec

TRAINS = ("metro", "hst", "freight")
ENGINE_TOL_MEAN_DB = 0.05
ENGINE_TOL_COHERENT_DB = 0.3
"""|SBR - image| bounds of the cross-validation test in the square tunnel (local mean, coherent) [dB]."""
SOURCE_P95 = {"metro": (1.5, 1.2, 1.8), "hst": (2.0, 1.5, 2.5), "freight": (3.5, 2.0, 5.0)}
"""seed 003 §8.1: 95 % accuracy of the train, its head and its tail [m] (stated as ±)."""


def _add(s: dict[str, KeySpec], name, unit, desc, src=None, rel=None, digits=3) -> None:
    s[name] = KeySpec(name, unit, desc, src, rel, digits)


def _train_specs(s: dict[str, KeySpec]) -> None:
    """Per train type: the accuracy of every estimator and receiver (seed 8.1)."""
    for tr in TRAINS:
        tot, head, tail = SOURCE_P95[tr]
        _add(
            s,
            f"tunnel.{tr}.err_m.p95",
            "m",
            f"{tr}: 95th pct of the train error sqrt((e_h^2+e_t^2)/2), KF, "
            "separable receiver, delay errors white in time [ours: the source gives no time structure]",
            tot,
            "=",
        )
        _add(
            s,
            f"tunnel.{tr}.ar1.err_m.p95",
            "m",
            f"{tr}: the same with an AR(1) delay error along the track (measurement.delay_corr_m), same sigma",
        )
        _add(
            s,
            f"tunnel.{tr}.slot_bias.err_m.p95",
            "m",
            f"{tr}: the same with one constant delay bias per slot "
            "(the source's systematic per-slot errors), same sigma",
        )
        _add(s, f"tunnel.{tr}.head_err_m.p95", "m", f"{tr}: 95th pct of the head error, KF", head, "=")
        _add(s, f"tunnel.{tr}.tail_err_m.p95", "m", f"{tr}: 95th pct of the tail error, KF", tail, "=")
        _add(s, f"tunnel.{tr}.rigid.err_m.p95", "m", f"{tr}: 95th pct, rigid-train KF on all receivers")
        _add(s, f"tunnel.{tr}.pf.err_m.p95", "m", f"{tr}: 95th pct, particle filter")
        _add(s, f"tunnel.{tr}.snapshot.err_m.p95", "m", f"{tr}: 95th pct of the head receiver's TDOA snapshot error")
        _add(s, f"tunnel.{tr}.rssi.err_m.p95", "m", f"{tr}: 95th pct of the head receiver's RSSI-ranging LS error")
        _add(s, f"tunnel.{tr}.wideband.err_m.p95", "m", f"{tr}: 95th pct of the train error, KF, wideband receiver")
        _add(
            s, f"tunnel.{tr}.seed_channel.err_m.p95", "m", f"{tr}: 95th pct of the train error, KF, the seed's channel"
        )
        _add(
            s,
            f"tunnel.{tr}.length_err_m.p95",
            "m",
            f"{tr}: 95th pct of |estimated head-tail distance - train length|, KF (the observable "
            "part of the attitude: with collinear slots the lateral offset, hence the seed's "
            "attitude angle, is not observable)",
        )


def _coverage_specs(s: dict[str, KeySpec]) -> None:
    """Coverage, blind spots, availability and the wideband receiver's fixes."""
    _add(
        s,
        "tunnel.coverage_frac",
        "1",
        "share of the tunnel with local-mean RSSI >= -95 dBm (physical, image)",
        0.96,
        "≥",
    )
    _add(s, "tunnel.coverage_frac.coherent", "1", "same with the coherent RSSI (fading included)")
    _add(s, "tunnel.coverage_frac.sbr_circle", "1", "same, SBR in the circular cross-section")
    _add(s, "tunnel.coverage_frac.seed_model", "1", "same, the seed's propagation model")
    _add(s, "tunnel.blind_spot_frac", "1", "share of the tunnel in a blind spot (seed 5.1.2), physical")
    _add(s, "tunnel.blind_spot_frac.seed_model", "1", "share in a blind spot, the seed's model")
    _add(s, "tunnel.availability.err_lt_5m", "1", "share of epochs with train error < 5 m (KF, all trains)", 0.95, "≥")
    _add(s, "tunnel.availability.err_lt_2m", "1", "share of epochs with train error < 2 m (KF, all trains)", 0.85, "≥")
    _add(s, "tunnel.availability.wideband.err_lt_5m", "1", "same, < 5 m, wideband receiver")
    _add(
        s,
        "tunnel.wideband.ambiguity_wrong_frac",
        "1",
        "share of wideband snapshot fixes (all trains and receivers) whose side of the feed (or feed) "
        "the measurements resolved wrongly (chosen candidate > one slot spacing from the right one)",
        digits=4,
    )
    _add(
        s,
        "tunnel.wideband.snapshot.err_m.p95",
        "m",
        "95th pct of the wideband snapshot error (all trains and receivers)",
    )
    _add(
        s,
        "tunnel.wideband.peak_bias_ns",
        "ns",
        "median CIR-peak delay minus the cable-point model delay on the calibration runs (mean over trains)",
        digits=2,
    )


def _channel_specs(s: dict[str, KeySpec]) -> None:
    """The channel along the tunnel, the ray engines, the HST snapshot geometry."""
    _add(s, "tunnel.delay_spread_ns.median", "ns", "median RMS delay spread along the tunnel (physical, image)")
    _add(s, "tunnel.delay_spread_ns.median.seed_model", "ns", "median RMS delay spread, the seed's model")
    _add(s, "tunnel.rssi_dbm.median", "dBm", "median local-mean RSSI (physical, image)")
    _add(s, "tunnel.rssi_dbm.median.seed_model", "dBm", "median local-mean RSSI, the seed's model")
    _add(s, "tunnel.rays.order", "1", "reflection order chosen by the convergence criterion")
    _add(s, "tunnel.rays.families_image", "1", "image-method rays (families) per slot")
    _add(s, "tunnel.rays.families_sbr_circle", "1", "SBR ray families per slot, circular cross-section")
    _add(
        s,
        "tunnel.engines.rect_max_diff_db",
        "dB",
        "largest |SBR - image| local-mean gain in the square tunnel",
        digits=2,
    )
    _add(
        s,
        "tunnel.engines.test_tol_mean_db",
        "dB",
        "tolerance of the engine cross-validation test, local-mean gain",
        digits=2,
    )
    _add(
        s,
        "tunnel.engines.test_tol_coherent_db",
        "dB",
        "tolerance of the engine cross-validation test, coherent gain",
        digits=2,
    )
    _add(s, "tunnel.hst.cep_m", "m", "HST: CEP = 0.59 sigma_x (seed 4.3.2) of the TDOA snapshot, sigma_y = 0")
    _add(s, "tunnel.hst.snapshot.err_m.p50", "m", "HST: median TDOA snapshot error (the CEP's empirical counterpart)")
    _add(s, "tunnel.hst.gdop_seed.median", "1", "HST head receiver: median of the seed's 2-D GDOP")
    _add(s, "tunnel.hst.gdop_tdoa.median", "1", "HST head receiver: median along-track TDOA dilution")


def _ray_check_specs(s: dict[str, KeySpec]) -> None:
    """The lining's reflection, the far decay and the table's cut-off."""
    _add(
        s,
        "tunnel.fresnel.normal_loss_db",
        "dB",
        "Fresnel reflection loss of the lining at normal incidence",
        8.0,
        "=",
        2,
    )
    _add(s, "tunnel.fresnel.te_loss_db.graze1deg", "dB", "TE reflection loss at 1 degree grazing", digits=2)
    _add(s, "tunnel.fresnel.te_loss_db.graze10deg", "dB", "TE reflection loss at 10 degrees grazing", digits=2)
    _add(s, "tunnel.fresnel.tm_loss_db.graze10deg", "dB", "TM reflection loss at 10 degrees grazing", digits=2)
    _add(
        s,
        "tunnel.modal_att_db_per_m",
        "dB/m",
        "EH11 modal attenuation of the square tunnel (Emslie, Lagace & "
        "Strong 1975), a theoretical value with no counterpart in the source",
        digits=2,
    )
    _add(
        s,
        "tunnel.rays.local_mean_slope_db_per_km.1500_5000",
        "dB/km",
        "decay of one slot's local mean (coherent power averaged over one EH11-EH12 beat length) fitted over "
        "rays.far_decay_m, image method at rays.max_order (test: within -0.5/+1.0 dB/km of the EH11 attenuation)",
        digits=2,
    )
    _add(
        s,
        "tunnel.rays.far_converged_order",
        "1",
        "lowest order whose far local means lie within 0.1 dB of the "
        "max_order ones (the slope key's order is converged when this is below rays.max_order)",
    )
    _add(
        s,
        "tunnel.rays.table_extent_m",
        "m",
        "largest slot-receiver offset of the image-method table (rays.max_offset_m; null: the whole tunnel)",
        digits=0,
    )
    _add(
        s,
        "tunnel.rays.power_beyond_cutoff_frac.p95",
        "1",
        "95th pct along the tunnel of the local-mean power share "
        "from slots beyond the table's extent (the criterion: at most rays.cutoff_power_frac)",
        digits=2,
    )
    _add(
        s,
        "tunnel.delay_spread_ns.cutoff_sensitivity",
        "1",
        "relative change of the median RMS delay spread when "
        "the table's extent doubles (image method, receivers every 2 m; test: at most 0.05)",
        digits=2,
    )
    _add(
        s,
        "tunnel.delay_spread_ns.half_extent_change",
        "1",
        "relative change of the median RMS delay spread when the table's extent halves (how much the far slots count)",
        digits=2,
    )


def _delay_error_and_guide_specs(s: dict[str, KeySpec]) -> None:
    """The wideband delay error, the circular guide, one slot's incoherent excess."""
    _add(
        s,
        "tunnel.wideband.delay_error_ns.robust_sigma",
        "ns",
        "the wideband receiver's own delay error (peak "
        "delay minus the calibrated model at the true position): 1.4826 x median absolute deviation, all trains "
        "and receivers",
        digits=1,
    )
    _add(
        s,
        "tunnel.wideband.delay_error_ns.p99",
        "ns",
        "99th pct of the absolute wideband delay error (its heavy tail)",
        digits=0,
    )
    _add(
        s,
        "tunnel.wideband.delay_error.lag1_autocorr",
        "1",
        "correlation of the wideband delay error between "
        "consecutive epochs of one receiver (rank correlation, all trains): its time structure",
        digits=2,
    )
    _add(
        s,
        "tunnel.rays.sbr_circle.local_mean_slope_db_per_km",
        "dB/km",
        "the circular engine (SBR): one slot's far "
        "local-mean decay over rays.far_decay_m at rays.max_order, as for the square",
        digits=2,
    )
    _add(
        s,
        "tunnel.rays.circle_eh11_db_per_km",
        "dB/km",
        "EH11 attenuation of a lossy circular guide of the tunnel's diameter (Marcatili & Schmeltzer 1964)",
        digits=2,
    )
    _add(
        s,
        "tunnel.rays.circle_te01_db_per_km",
        "dB/km",
        "TE01 attenuation of the same guide, the lowest of any mode (Marcatili & Schmeltzer 1964)",
        digits=2,
    )
    _add(s, "tunnel.rays.beat_length_m", "m", "EH11-EH12 beat length 8a^2/(3 lambda) of the square tunnel", digits=0)
    _add(
        s,
        "tunnel.rays.incoherent_excess_db.1000",
        "dB",
        "one slot's incoherent ray-power sum above its local mean "
        "(the coherent power averaged over 40 wavelengths) at 1000 m: the error of the incoherent local mean",
        digits=1,
    )
    _add(s, "tunnel.slot_eirp_db_re_cable", "dB", "slot EIRP relative to the cable power (slot-chain calibration)")


def _peak_bias_and_side_wall_specs(s: dict[str, KeySpec]) -> None:
    """The wideband peak bias by channel case and the side-wall cable."""
    for case, what in (
        ("single_slot", "the nearest slot's line-of-sight ray alone"),
        ("los_slots", "every slot's line-of-sight ray in the receiver's window (absorbing walls)"),
        ("full", "the full channel in the receiver's window"),
        ("full_all_slots", "the full channel of every tabulated slot"),
    ):
        _add(
            s,
            f"tunnel.wideband.peak_bias_ns.{case}.median",
            "ns",
            f"median noiseless CIR-peak delay minus the cable-point model delay along the tunnel: {what}",
            digits=2,
        )
    _add(
        s,
        "tunnel.sens.slot_side_wall.delay_spread_ns.median",
        "ns",
        "median RMS delay spread along the tunnel, cable on the side wall (physical, positioning engine)",
    )
    _add(s, "tunnel.sens.slot_side_wall.rssi_dbm.median", "dBm", "median local-mean RSSI, cable on the side wall")
    _add(
        s,
        "tunnel.sens.slot_side_wall.cross_distance_m",
        "m",
        "slot-line-to-antenna distance in the cross-section, side wall",
        digits=2,
    )
    _add(s, "tunnel.wideband.peak_bias_ns.full.p5", "ns", "5th pct of the same, full channel in the window", digits=1)
    _add(s, "tunnel.wideband.peak_bias_ns.full.p95", "ns", "95th pct of the same, full channel in the window", digits=1)


def _specs() -> dict[str, KeySpec]:
    s: dict[str, KeySpec] = {}
    _train_specs(s)
    _coverage_specs(s)
    _channel_specs(s)
    _ray_check_specs(s)
    _delay_error_and_guide_specs(s)
    _peak_bias_and_side_wall_specs(s)
    return s


SPECS = _specs()


def sens_spec(case: str, train: str) -> KeySpec:
    """Key of one sensitivity case and train type (names follow the config's cases)."""
    return KeySpec(
        f"tunnel.sens.{case}.{train}.err_m.p95",
        "m",
        f"{train}: 95th pct of the train error, KF, sensitivity case {case} (pooled over realizations)",
    )


def length_error_m(ds: xr.Dataset) -> np.ndarray:
    """|x̂_head - x̂_tail - L| per epoch [m] of a run's KF (realization 0): the train's
    along-track extent, all that remains of the seed's attitude θ = arctan(Δy/Δx)
    (seed 3.3.2) when the slots are collinear and only along-track positions are solved."""
    return np.abs(ds["kf_head"].values - ds["kf_tail"].values - float(ds.attrs["length_m"]))


def pooled_p95(rep: np.ndarray) -> tuple[float, float | None]:
    """95th percentile of errors [realization, epoch] pooled over realizations, and its Monte
    Carlo standard error: the std of the per-realization 95th percentiles / sqrt(R)
    (None for one realization)."""
    rep = np.asarray(rep, dtype=float)
    value = float(np.nanpercentile(rep, 95))
    if rep.shape[0] < 2:
        return value, None
    per = np.nanpercentile(rep, 95, axis=1)
    return value, float(np.std(per, ddof=1) / np.sqrt(per.size))


def pooled_share(reps: list[np.ndarray], limit_m: float) -> tuple[float, float | None]:
    """Share of epochs with error < limit over all runs [realization, epoch] (same R each)
    and its Monte Carlo standard error across realizations."""
    value = float(np.mean(np.concatenate([r.ravel() for r in reps]) < limit_m))
    n_r = reps[0].shape[0]
    if n_r < 2 or any(r.shape[0] != n_r for r in reps):
        return value, None
    per = np.array([np.mean(np.concatenate([r[i] for r in reps]) < limit_m) for i in range(n_r)])
    return value, float(np.std(per, ddof=1) / np.sqrt(n_r))


def _put(out: dict[str, Any], name: str, value, se=None) -> None:
    out[name] = SPECS[name].entry(None if value is None else float(value), se)


def _p95(v) -> float:
    return np.nanpercentile(np.asarray(v), 95)


def _run_keys(out: dict[str, Any], runs: dict[tuple[str, str], xr.Dataset]) -> list[xr.Dataset]:
    """Every train's accuracy keys and the availabilities; returns the wideband runs."""
    pooled, pooled_wb = [], []
    for tr in TRAINS:
        ds = runs[(tr, "physical_separable")]
        _put(out, f"tunnel.{tr}.err_m.p95", *pooled_p95(ds["rep_err"].values))
        _put(out, f"tunnel.{tr}.head_err_m.p95", *pooled_p95(ds["rep_err_head"].values))
        _put(out, f"tunnel.{tr}.tail_err_m.p95", *pooled_p95(ds["rep_err_tail"].values))
        _put(out, f"tunnel.{tr}.rigid.err_m.p95", _p95(ds["rigid_err"]))
        _put(out, f"tunnel.{tr}.length_err_m.p95", _p95(length_error_m(ds)))
        _put(out, f"tunnel.{tr}.pf.err_m.p95", _p95(ds["pf_err"]))
        _put(out, f"tunnel.{tr}.snapshot.err_m.p95", _p95(ds["snapshot_err"].values[:, 0]))
        _put(out, f"tunnel.{tr}.rssi.err_m.p95", _p95(ds["snapshot_rssi_err"].values[:, 0]))
        pooled.append(ds["rep_err"].values)
        for v, k in (("physical_separable_ar1", "ar1"), ("physical_separable_slot_bias", "slot_bias")):
            r = runs.get((tr, v))
            _put(out, f"tunnel.{tr}.{k}.err_m.p95", *((None, None) if r is None else pooled_p95(r["rep_err"].values)))
        wb = runs.get((tr, "physical_wideband"))
        _put(out, f"tunnel.{tr}.wideband.err_m.p95", None if wb is None else _p95(wb["kf_err"]))
        if wb is not None:
            pooled_wb.append(wb)
        sd = runs.get((tr, "seed_separable"))
        _put(
            out,
            f"tunnel.{tr}.seed_channel.err_m.p95",
            *((None, None) if sd is None else pooled_p95(sd["rep_err"].values)),
        )
    _put(out, "tunnel.availability.err_lt_5m", *pooled_share(pooled, 5.0))
    _put(out, "tunnel.availability.err_lt_2m", *pooled_share(pooled, 2.0))
    return pooled_wb


def _wideband_keys(out: dict[str, Any], pooled_wb: list[xr.Dataset]) -> None:
    """The wideband receiver's delay error, availability, ambiguity and peak bias (all trains)."""
    if pooled_wb:
        from scipy.stats import median_abs_deviation, spearmanr

        err = np.concatenate([w["wideband_delay_error"].values.ravel() for w in pooled_wb]) * 1e9
        err = err[np.isfinite(err)]
        _put(out, "tunnel.wideband.delay_error_ns.robust_sigma", 1.4826 * median_abs_deviation(err, axis=None))
        _put(out, "tunnel.wideband.delay_error_ns.p99", np.percentile(np.abs(err), 99))
        a = np.concatenate([w["wideband_delay_error"].values[:-1].ravel() for w in pooled_wb])
        b = np.concatenate([w["wideband_delay_error"].values[1:].ravel() for w in pooled_wb])
        ok = np.isfinite(a) & np.isfinite(b)
        _put(out, "tunnel.wideband.delay_error.lag1_autocorr", spearmanr(a[ok], b[ok])[0])
    else:
        for k in ("delay_error_ns.robust_sigma", "delay_error_ns.p99", "delay_error.lag1_autocorr"):
            _put(out, f"tunnel.wideband.{k}", None)
    cat = (lambda v: np.concatenate([w[v].values.ravel() for w in pooled_wb])) if pooled_wb else None
    _put(out, "tunnel.availability.wideband.err_lt_5m", np.mean(cat("kf_err") < 5.0) if cat else None)
    _put(out, "tunnel.wideband.ambiguity_wrong_frac", np.mean(cat("ambiguity_wrong")) if cat else None)
    _put(out, "tunnel.wideband.snapshot.err_m.p95", _p95(cat("snapshot_err")) if cat else None)
    _put(
        out,
        "tunnel.wideband.peak_bias_ns",
        np.mean([w.attrs["wideband_bias_s"] for w in pooled_wb]) * 1e9 if pooled_wb else None,
    )


def _map_keys(
    out: dict[str, Any],
    maps: dict[str, xr.Dataset],
    tables: dict[str, xr.Dataset],
    engines: xr.Dataset,
    coverage_dbm: float,
    blind_dbm: float,
    min_rays: int,
) -> None:
    """Coverage, blind spots, delay spread and RSSI along the tunnel; the rays; the engines."""

    def blind(m):  # seed 5.1.2: RSSI_max < -100 dBm or fewer than 3 usable rays
        return np.mean((m["rssi_mean_dbm"].values < blind_dbm) | (m["n_strong_rays"].values < min_rays))

    _put(out, "tunnel.coverage_frac", np.mean(maps["image"]["rssi_mean_dbm"].values >= coverage_dbm))
    _put(out, "tunnel.coverage_frac.coherent", np.mean(maps["image"]["rssi_coherent_dbm"].values >= coverage_dbm))
    _put(out, "tunnel.coverage_frac.sbr_circle", np.mean(maps["sbr"]["rssi_mean_dbm"].values >= coverage_dbm))
    _put(out, "tunnel.coverage_frac.seed_model", np.mean(maps["seed"]["rssi_mean_dbm"].values >= coverage_dbm))
    _put(out, "tunnel.blind_spot_frac", blind(maps["image"]))
    _put(out, "tunnel.blind_spot_frac.seed_model", blind(maps["seed"]))
    _put(out, "tunnel.delay_spread_ns.median", np.median(maps["image"]["delay_rms_s"].values) * 1e9)
    _put(out, "tunnel.delay_spread_ns.median.seed_model", np.median(maps["seed"]["delay_rms_s"].values) * 1e9)
    _put(out, "tunnel.rssi_dbm.median", np.median(maps["image"]["rssi_mean_dbm"].values))
    _put(out, "tunnel.rssi_dbm.median.seed_model", np.median(maps["seed"]["rssi_mean_dbm"].values))
    _put(out, "tunnel.rays.order", tables["image"].attrs["reflection_order"])
    _put(out, "tunnel.rays.families_image", tables["image"].attrs["n_families"])
    _put(out, "tunnel.rays.families_sbr_circle", tables["sbr"].attrs["n_families"])
    diff = engines["power_mean_db"].sel(model="sbr_rect") - engines["power_mean_db"].sel(model="image_rect")
    _put(out, "tunnel.engines.rect_max_diff_db", float(np.max(np.abs(diff.values))))
    _put(out, "tunnel.engines.test_tol_mean_db", ENGINE_TOL_MEAN_DB)
    _put(out, "tunnel.engines.test_tol_coherent_db", ENGINE_TOL_COHERENT_DB)


def _hst_and_lining_keys(
    out: dict[str, Any], runs: dict[tuple[str, str], xr.Dataset], wavelength_m: float, side_m: float, eps: complex
) -> None:
    """The HST snapshot's CEP and dilutions; the lining's reflection losses and the EH11 attenuation."""
    from railradio.tunnel.materials import eh11_attenuation_db_per_m, fresnel_te, fresnel_tm, reflection_loss_db

    hst = runs[("hst", "physical_separable")]
    e = hst["snapshot"].values[:, 0] - hst["x_rx_true"].values[:, 0]
    _put(out, "tunnel.hst.cep_m", 0.59 * np.std(e))
    _put(out, "tunnel.hst.snapshot.err_m.p50", np.median(np.abs(e)))
    _put(out, "tunnel.hst.gdop_seed.median", np.median(hst["gdop_seed"].values[:, 0]))
    _put(out, "tunnel.hst.gdop_tdoa.median", np.median(hst["gdop_tdoa"].values[:, 0]))
    _put(out, "tunnel.fresnel.normal_loss_db", reflection_loss_db(fresnel_te(1.0, eps)))
    _put(out, "tunnel.fresnel.te_loss_db.graze1deg", reflection_loss_db(fresnel_te(np.sin(np.deg2rad(1.0)), eps)))
    _put(out, "tunnel.fresnel.te_loss_db.graze10deg", reflection_loss_db(fresnel_te(np.sin(np.deg2rad(10.0)), eps)))
    _put(out, "tunnel.fresnel.tm_loss_db.graze10deg", reflection_loss_db(fresnel_tm(np.sin(np.deg2rad(10.0)), eps)))
    _put(out, "tunnel.modal_att_db_per_m", eh11_attenuation_db_per_m(wavelength_m, side_m, side_m, eps))


def _table_keys(out: dict[str, Any], tables: dict[str, xr.Dataset], engines: xr.Dataset) -> None:
    """The image table's far decay, cut-off and slot EIRP; the circular engine's far decay."""
    t = tables["image"]
    off = t["offset_m"].values
    _put(out, "tunnel.rays.local_mean_slope_db_per_km.1500_5000", engines.attrs["far_slope_db_per_km"])
    _put(out, "tunnel.rays.far_converged_order", engines.attrs["far_converged_order"])
    _put(out, "tunnel.rays.beat_length_m", engines.attrs["far_beat_length_m"])
    _put(out, "tunnel.rays.sbr_circle.local_mean_slope_db_per_km", engines.attrs["far_circle_slope_db_per_km"])
    _put(out, "tunnel.rays.circle_eh11_db_per_km", engines.attrs["far_circle_eh11_db_per_km"])
    _put(out, "tunnel.rays.circle_te01_db_per_km", engines.attrs["far_circle_te01_db_per_km"])
    _put(out, "tunnel.rays.power_beyond_cutoff_frac.p95", np.percentile(engines["power_beyond_cutoff_frac"].values, 95))
    ds_med = {k: float(np.median(engines[f"delay_rms_{k}_s"].values)) for k in ("halved", "cutoff", "doubled")}
    _put(out, "tunnel.rays.table_extent_m", engines.attrs["cutoff_m"])
    _put(out, "tunnel.delay_spread_ns.cutoff_sensitivity", ds_med["doubled"] / ds_med["cutoff"] - 1.0)
    _put(out, "tunnel.delay_spread_ns.half_extent_change", ds_med["halved"] / ds_med["cutoff"] - 1.0)
    if off[-1] >= 1000.0:
        i = int(np.argmin(np.abs(off - 1000.0)))
        _put(
            out,
            "tunnel.rays.incoherent_excess_db.1000",
            10 * np.log10(t["power_incoherent"].values[i] / t["power_mean"].values[i]),
        )
    else:
        _put(out, "tunnel.rays.incoherent_excess_db.1000", None)
    _put(out, "tunnel.slot_eirp_db_re_cable", t.attrs["slot_eirp_offset_db"])


def _sensitivity_keys(
    out: dict[str, Any],
    sens: dict[str, xr.Dataset] | None,
    peak_bias: xr.Dataset | None,
    side_wall_map: xr.Dataset | None,
) -> None:
    """The wideband peak bias by channel case, the side-wall cable, every sensitivity case."""
    if peak_bias is not None:
        for case, b in zip(peak_bias["case"].values, peak_bias["peak_bias_s"].values, strict=True):
            _put(out, f"tunnel.wideband.peak_bias_ns.{case}.median", np.median(b) * 1e9)
        full = peak_bias["peak_bias_s"].sel(case="full").values * 1e9
        _put(out, "tunnel.wideband.peak_bias_ns.full.p5", np.percentile(full, 5))
        _put(out, "tunnel.wideband.peak_bias_ns.full.p95", np.percentile(full, 95))
    if side_wall_map is not None:
        _put(
            out,
            "tunnel.sens.slot_side_wall.delay_spread_ns.median",
            np.median(side_wall_map["delay_rms_s"].values) * 1e9,
        )
        _put(out, "tunnel.sens.slot_side_wall.rssi_dbm.median", np.median(side_wall_map["rssi_mean_dbm"].values))
        _put(out, "tunnel.sens.slot_side_wall.cross_distance_m", side_wall_map.attrs["cross_distance_m"])
    for tr, sd in (sens or {}).items():
        for i, case in enumerate(sd["case"].values):
            per = sd["rep_err_p95_m"].values[i]
            se = float(np.std(per, ddof=1) / np.sqrt(per.size)) if per.size > 1 else None
            out[sens_spec(str(case), tr).name] = sens_spec(str(case), tr).entry(float(sd["err_p95_m"].values[i]), se)


def key_numbers(
    runs: dict[tuple[str, str], xr.Dataset],
    maps: dict[str, xr.Dataset],
    tables: dict[str, xr.Dataset],
    engines: xr.Dataset,
    coverage_dbm: float,
    blind_dbm: float,
    min_rays: int,
    wavelength_m: float,
    side_m: float,
    eps: complex,
    sens: dict[str, xr.Dataset] | None = None,
    peak_bias: xr.Dataset | None = None,
    side_wall_map: xr.Dataset | None = None,
) -> dict[str, Any]:
    """The key numbers ``tunnel.*`` (:data:`SPECS`, with the sensitivity cases' keys of
    :func:`sens_spec`) from the study's intermediates, beside the seed's design targets.

    Parameters
    ----------
    runs : dict
        (train, variant) -> run of :func:`railradio.tunnel.simulate.run_train`; needs
        ``physical_separable`` for every train of :data:`TRAINS` (``hst`` also gives the CEP
        and dilutions); the other variants of :data:`railradio.tunnel.study.VARIANTS` are
        optional (their keys null when missing).
    maps : dict
        Table name -> map of :func:`railradio.tunnel.study.make_map`; needs ``image``,
        ``sbr`` and ``seed``.
    tables : dict
        Table name -> table of :func:`railradio.tunnel.study.make_table`; needs ``image``
        and ``sbr``.
    engines : xarray.Dataset
        The engine checks of :func:`railradio.tunnel.engine_checks.make_engines`.
    coverage_dbm : float
        Coverage threshold of the local-mean RSSI [dBm].
    blind_dbm : float
        Blind-spot level of the local-mean RSSI [dBm].
    min_rays : int
        Fewest strong rays (the maps' ``n_strong_rays``) outside a blind spot.
    wavelength_m : float
        Carrier wavelength [m] (EH11 attenuation).
    side_m : float
        Side of the square tunnel of equal area [m] (EH11 attenuation).
    eps : complex
        Relative permittivity of the wall [1] (Fresnel losses, EH11 attenuation).
    sens : dict or None
        Train -> sensitivity cases of :func:`railradio.tunnel.sensitivity.make_sensitivity`;
        None: no sensitivity keys.
    peak_bias : xarray.Dataset or None
        The peak-bias cases of :func:`railradio.tunnel.peak_bias.make_peak_bias`; None: not reported.
    side_wall_map : xarray.Dataset or None
        The map of the side-wall table (:func:`railradio.tunnel.study.make_map`); None: not reported.

    Returns
    -------
    dict
        Key name -> JSON entry of :meth:`railradio.keynumbers.KeySpec.entry` (``value`` in
        the key's ``unit``, ``mc_stderr`` where realizations give one, the source's value
        and relation, description, digits).

    Raises
    ------
    ValueError
        When a key's value is not finite.
    """
    out: dict[str, Any] = {}
    pooled_wb = _run_keys(out, runs)
    _wideband_keys(out, pooled_wb)
    _map_keys(out, maps, tables, engines, coverage_dbm, blind_dbm, min_rays)
    _hst_and_lining_keys(out, runs, wavelength_m, side_m, eps)
    _table_keys(out, tables, engines)
    _sensitivity_keys(out, sens, peak_bias, side_wall_map)
    return out
