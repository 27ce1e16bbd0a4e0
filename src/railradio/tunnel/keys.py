"""Key numbers of the tunnel study (docs/model/tunnel.md; source values from source 003 §8)."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from railradio.tunnel.key_specs import ENGINE_TOL_COHERENT_DB, ENGINE_TOL_MEAN_DB, SPECS, TRAINS, sens_spec


def length_error_m(ds: xr.Dataset) -> np.ndarray:
    """|x̂_head - x̂_tail - L| per epoch [m] of a run's KF (realization 0): the train's
    along-track extent, all that remains of the source's attitude θ = arctan(Δy/Δx)
    (source 3.3.2) when the slots are collinear and only along-track positions are solved.

    Parameters
    ----------
    ds : xarray.Dataset
        A run of :func:`railradio.tunnel.simulate.run_train`: ``kf_head``, ``kf_tail``
        [time_s] [m] and the attribute ``length_m`` (train length L) [m].

    Returns
    -------
    numpy.ndarray
        Train length error [time_s] [m].
    """
    return np.abs(ds["kf_head"].values - ds["kf_tail"].values - float(ds.attrs["length_m"]))


def pooled_p95(rep: np.ndarray) -> tuple[float, float | None]:
    """95th percentile of errors [realization, epoch] pooled over realizations, and its Monte
    Carlo standard error: the std of the per-realization 95th percentiles / sqrt(R)
    (None for one realization).

    Parameters
    ----------
    rep : numpy.ndarray
        Errors [realization, epoch] [m]; NaN is ignored.

    Returns
    -------
    tuple
        ``(value, stderr)``: the pooled 95th percentile [m] (float) and its Monte Carlo
        standard error [m] (float, or None with one realization).
    """
    rep = np.asarray(rep, dtype=float)
    value = float(np.nanpercentile(rep, 95))
    if rep.shape[0] < 2:
        return value, None
    per = np.nanpercentile(rep, 95, axis=1)
    return value, float(np.std(per, ddof=1) / np.sqrt(per.size))


def pooled_share(reps: list[np.ndarray], limit_m: float) -> tuple[float, float | None]:
    """Share of epochs with error < limit over all runs [realization, epoch] (same R each)
    and its Monte Carlo standard error across realizations.

    Parameters
    ----------
    reps : list of numpy.ndarray
        Errors of every run [realization, epoch] [m].
    limit_m : float
        Error limit [m].

    Returns
    -------
    tuple
        ``(value, stderr)``: the share of epochs with error < ``limit_m`` over all runs [1]
        (float) and its Monte Carlo standard error [1] (float, or None with fewer than two
        realizations or unequal numbers of realizations).
    """
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
        sd = runs.get((tr, "source_separable"))
        _put(
            out,
            f"tunnel.{tr}.source_channel.err_m.p95",
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

    def blind(m):  # source 5.1.2: RSSI_max < -100 dBm or fewer than 3 usable rays
        return np.mean((m["rssi_mean_dbm"].values < blind_dbm) | (m["n_strong_rays"].values < min_rays))

    _put(out, "tunnel.coverage_frac", np.mean(maps["image"]["rssi_mean_dbm"].values >= coverage_dbm))
    _put(out, "tunnel.coverage_frac.coherent", np.mean(maps["image"]["rssi_coherent_dbm"].values >= coverage_dbm))
    _put(out, "tunnel.coverage_frac.sbr_circle", np.mean(maps["sbr"]["rssi_mean_dbm"].values >= coverage_dbm))
    _put(out, "tunnel.coverage_frac.source_model", np.mean(maps["source"]["rssi_mean_dbm"].values >= coverage_dbm))
    _put(out, "tunnel.blind_spot_frac", blind(maps["image"]))
    _put(out, "tunnel.blind_spot_frac.source_model", blind(maps["source"]))
    _put(out, "tunnel.delay_spread_ns.median", np.median(maps["image"]["delay_rms_s"].values) * 1e9)
    _put(out, "tunnel.delay_spread_ns.median.source_model", np.median(maps["source"]["delay_rms_s"].values) * 1e9)
    _put(out, "tunnel.rssi_dbm.median", np.median(maps["image"]["rssi_mean_dbm"].values))
    _put(out, "tunnel.rssi_dbm.median.source_model", np.median(maps["source"]["rssi_mean_dbm"].values))
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
    _put(out, "tunnel.hst.gdop_source.median", np.median(hst["gdop_source"].values[:, 0]))
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
    :func:`sens_spec`) from the study's intermediates, beside the source's design targets.

    Parameters
    ----------
    runs : dict
        (train, setup) -> run of :func:`railradio.tunnel.simulate.run_train`; needs
        ``physical_separable`` for every train of :data:`TRAINS` (``hst`` also gives the CEP
        and dilutions); the other setups of :data:`railradio.tunnel.study.SETUPS` are
        optional (their keys null when missing).
    maps : dict
        Table name -> map of :func:`railradio.tunnel.study.make_map`; needs ``image``,
        ``sbr`` and ``source``.
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
