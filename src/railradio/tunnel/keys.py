"""Key numbers of the tunnel study (docs/model/tunnel.md; source values from source 003 §8)."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from railradio.nr.tracking import loss
from railradio.tunnel.key_specs import (
    DELAY_SPREAD_THRESHOLDS_DB,
    ENGINE_TOL_COHERENT_DB,
    ENGINE_TOL_MEAN_DB,
    SPECS,
    TRAINS,
    sens_spec,
)


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


RECEIVERS = ("separable", "wideband")
"""The two receivers whose runs every train has (``physical_<receiver>``)."""
WIDEBAND_CASES = {
    "wideband_slow": "physical_wideband_slow",
    "wideband_vf": "physical_wideband_vf",
    "wideband_feed": "physical_wideband_feed",
}
"""Key infix -> run setup of the wideband receiver's cases (:data:`railradio.tunnel.study.SETUPS`)."""


START_S = 2.0
"""Start-up of a filter [s]: it starts from one snapshot fix with the speed unknown by +-100 m/s,
and its first epochs' errors are its convergence, not a loss (:func:`lost_epochs`)."""


def lost_epochs(err_m: np.ndarray, slot_spacing_m: float, t_s: np.ndarray | None = None) -> np.ndarray:
    """Epochs whose track is lost: after the start-up (``t_s`` >= :data:`START_S`), error above
    one slot spacing (or NaN).  Beyond it the tracker follows another slot's delay or another
    candidate (the wrong side of a feed, the wrong feed:
    :func:`railradio.tunnel.wideband.ambiguity_wrong` uses the same bound), and the error says
    where the track went, not how accurate the receiver is.  A kept track stays below ~20 m in
    every run measured (the wideband receiver's worst: 19.5 m, feed-delay case), a lost one
    is kilometres off.

    Parameters
    ----------
    err_m : numpy.ndarray
        Position errors [m], [..., epoch].
    slot_spacing_m : float
        Slot spacing [m]; positive.
    t_s : numpy.ndarray or None
        Epoch times since the filter's start [s], [epoch]; None: every epoch is scored.

    Returns
    -------
    numpy.ndarray of bool
        True where lost, the shape of ``err_m``.

    Raises
    ------
    ValueError
        When ``slot_spacing_m`` is not positive.
    """
    if not slot_spacing_m > 0:
        raise ValueError(f"slot_spacing_m must be positive, got {slot_spacing_m!r}")
    lost = loss.lost_mask(err_m, 2.0 * slot_spacing_m)  # the nr rule's mask at half its spacing
    return lost if t_s is None else lost & (np.asarray(t_s) >= START_S)


def _pooled(out: dict[str, Any], name: str, ds: xr.Dataset | None, var: str = "rep_err", spacing: float = 20.0) -> None:
    """The pooled 95th percentile of ``var`` [realization, epoch] with its Monte Carlo error,
    null (with the lost share beside it) when the track is lost in 1 % of the epochs or more
    (:data:`railradio.nr.tracking.loss.LOST_FRAC_MAX`, the project's rule)."""
    if ds is None:
        _put(out, name, None)
        return
    rep = ds[var].values
    value, se = pooled_p95(rep)
    lost = float(np.mean(lost_epochs(rep, spacing, ds["time_s"].values)))
    acc = loss.accuracy(value, lost)
    out[name] = SPECS[name].entry(acc, se if acc is not None else None, lost)


def _track_keys(out: dict[str, Any], prefix: str, ds: xr.Dataset | None, spacing: float) -> None:
    """Over the epochs after the start-up (:data:`START_S`): ``<prefix>.lost_frac`` (share of
    lost epochs, with its Monte Carlo error), ``<prefix>.time_to_loss_s`` (mean over the
    realizations that lose the track of their first lost epoch) and
    ``<prefix>.tracked.err_m.p95`` (over the epochs not lost, with the spread of the
    realizations' own percentiles)."""
    if ds is None:
        for k in ("lost_frac", "time_to_loss_s", "tracked.err_m.p95"):
            _put(out, f"{prefix}.{k}", None)
        return
    t = ds["time_s"].values
    scored = t >= START_S
    rep, t = ds["rep_err"].values[:, scored], t[scored]
    lost = lost_epochs(rep, spacing)
    per = lost.mean(axis=1)
    se = float(np.std(per, ddof=1) / np.sqrt(per.size)) if per.size > 1 else None
    _put(out, f"{prefix}.lost_frac", float(lost.mean()), se)
    firsts = [float(t[np.argmax(row)]) for row in lost if row.any()]
    _put(out, f"{prefix}.time_to_loss_s", float(np.mean(firsts)) if firsts else None)
    kept = [np.percentile(row[~m], 95) for row, m in zip(rep, lost, strict=True) if (~m).any()]
    kept_se = float(np.std(kept, ddof=1) / np.sqrt(len(kept))) if len(kept) > 1 else None
    _put(out, f"{prefix}.tracked.err_m.p95", float(np.percentile(rep[~lost], 95)) if (~lost).any() else None, kept_se)


def _run_keys(
    out: dict[str, Any], runs: dict[tuple[str, str], xr.Dataset], headline: str, spacing: float
) -> list[xr.Dataset]:
    """Every train's accuracy keys and the availabilities: the headline receiver's under the
    plain names, both receivers' under ``<receiver>``, the wideband cases and the separable
    receiver's variants, each track's lost share (an error above one slot spacing,
    :func:`lost_epochs`); returns the wideband cruise runs."""
    pooled = {r: [] for r in RECEIVERS}
    pooled_wb = []
    for tr in TRAINS:
        ds = runs[(tr, f"physical_{headline}")]
        _pooled(out, f"tunnel.{tr}.err_m.p95", ds, spacing=spacing)
        _pooled(out, f"tunnel.{tr}.head_err_m.p95", ds, "rep_err_head", spacing)
        _pooled(out, f"tunnel.{tr}.tail_err_m.p95", ds, "rep_err_tail", spacing)
        _track_keys(out, f"tunnel.{tr}", ds, spacing)
        if "rep_err_rigid" in ds:
            _pooled(out, f"tunnel.{tr}.rigid.err_m.p95", ds, "rep_err_rigid", spacing)
        for est in ("pf",) if "rep_err_rigid" in ds else ("rigid", "pf"):
            e = ds[f"{est}_err"].values
            lost = float(np.mean(lost_epochs(e, spacing, ds["time_s"].values)))
            out[f"tunnel.{tr}.{est}.err_m.p95"] = SPECS[f"tunnel.{tr}.{est}.err_m.p95"].entry(
                loss.accuracy(_p95(e), lost), None, lost
            )
        _put(out, f"tunnel.{tr}.length_err_m.p95", _p95(length_error_m(ds)))
        _put(out, f"tunnel.{tr}.snapshot.err_m.p95", _p95(ds["snapshot_err"].values[:, 0]))
        for rec in RECEIVERS:
            r = runs.get((tr, f"physical_{rec}"))
            _pooled(out, f"tunnel.{tr}.{rec}.err_m.p95", r, spacing=spacing)
            _track_keys(out, f"tunnel.{tr}.{rec}", r, spacing)
            if r is not None:
                pooled[rec].append(r["rep_err"].values)
        sep = runs.get((tr, "physical_separable"))
        _put(out, f"tunnel.{tr}.rssi.err_m.p95", None if sep is None else _p95(sep["snapshot_rssi_err"].values[:, 0]))
        for v, k in (("physical_separable_ar1", "ar1"), ("physical_separable_slot_bias", "slot_bias")):
            _pooled(out, f"tunnel.{tr}.{k}.err_m.p95", runs.get((tr, v)), spacing=spacing)
        _pooled(out, f"tunnel.{tr}.source_channel.err_m.p95", runs.get((tr, "source_separable")), spacing=spacing)
        for k, setup in WIDEBAND_CASES.items():
            _pooled(out, f"tunnel.{tr}.{k}.err_m.p95", runs.get((tr, setup)), spacing=spacing)
            _track_keys(out, f"tunnel.{tr}.{k}", runs.get((tr, setup)), spacing)
        if (tr, "physical_wideband") in runs:
            pooled_wb.append(runs[(tr, "physical_wideband")])
    for lim in (5, 2):
        _put(out, f"tunnel.availability.err_lt_{lim}m", *pooled_share(pooled[headline], float(lim)))
        for rec in RECEIVERS:
            share = pooled_share(pooled[rec], float(lim)) if pooled[rec] else (None, None)
            _put(out, f"tunnel.availability.{rec}.err_lt_{lim}m", *share)
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
    _put(out, "tunnel.coverage_frac.source_model", np.mean(maps["source"]["rssi_mean_dbm"].values >= coverage_dbm))
    _put(out, "tunnel.blind_spot_frac", blind(maps["image"]))
    _put(out, "tunnel.blind_spot_frac.source_model", blind(maps["source"]))
    _put(out, "tunnel.delay_spread_ns.median", np.median(maps["image"]["delay_rms_s"].values) * 1e9)
    _put(out, "tunnel.delay_spread_ns.median.source_model", np.median(maps["source"]["delay_rms_s"].values) * 1e9)
    for thr in DELAY_SPREAD_THRESHOLDS_DB:
        for name, suffix in (("image", ""), ("source", ".source_model")):
            v = maps[name].get(f"delay_rms_thr{thr:g}_s")
            _put(out, f"tunnel.delay_spread_ns.thr{thr:g}.median{suffix}", None if v is None else np.median(v) * 1e9)
        v = maps["image"].get(f"delay_rms_thr{thr:g}_s")
        _put(out, f"tunnel.delay_spread_ns.thr{thr:g}.p90", None if v is None else np.percentile(v, 90) * 1e9)
    _put(out, "tunnel.rssi_dbm.median", np.median(maps["image"]["rssi_mean_dbm"].values))
    _put(out, "tunnel.rssi_dbm.median.source_model", np.median(maps["source"]["rssi_mean_dbm"].values))
    _put(out, "tunnel.rays.order", tables["image"].attrs["reflection_order"])
    _put(out, "tunnel.rays.families_image", tables["image"].attrs["n_families"])
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
    _put(out, "tunnel.hst.separable.snapshot.err_m.p50", np.median(np.abs(e)))
    _put(out, "tunnel.hst.separable.snapshot.err_m.p95", np.percentile(np.abs(e), 95))
    _put(out, "tunnel.hst.gdop_source.median", np.median(hst["gdop_source"].values[:, 0]))
    _put(out, "tunnel.hst.gdop_tdoa.median", np.median(hst["gdop_tdoa"].values[:, 0]))
    _put(out, "tunnel.fresnel.normal_loss_db", reflection_loss_db(fresnel_te(1.0, eps)))
    _put(out, "tunnel.fresnel.te_loss_db.graze1deg", reflection_loss_db(fresnel_te(np.sin(np.deg2rad(1.0)), eps)))
    _put(out, "tunnel.fresnel.te_loss_db.graze10deg", reflection_loss_db(fresnel_te(np.sin(np.deg2rad(10.0)), eps)))
    _put(out, "tunnel.fresnel.tm_loss_db.graze10deg", reflection_loss_db(fresnel_tm(np.sin(np.deg2rad(10.0)), eps)))
    _put(out, "tunnel.modal_att_db_per_m", eh11_attenuation_db_per_m(wavelength_m, side_m, side_m, eps))


def _table_keys(out: dict[str, Any], tables: dict[str, xr.Dataset], engines: xr.Dataset) -> None:
    """The image table's far decay, cut-off and slot EIRP; the circle's modal far decay and
    the retired SBR engine's gap to it."""
    t = tables["image"]
    off = t["offset_m"].values
    _put(out, "tunnel.rays.local_mean_slope_db_per_km.1500_5000", engines.attrs["far_slope_db_per_km"])
    _put(out, "tunnel.rays.far_converged_order", engines.attrs["far_converged_order"])
    _put(out, "tunnel.rays.modal_slope_db_per_km.1500_5000", engines.attrs.get("far_modal_slope_db_per_km"))
    _put(out, "tunnel.rays.modal_max_diff_db", engines.attrs.get("far_modal_max_diff_db"))
    _put(out, "tunnel.rays.beat_length_m", engines.attrs["far_beat_length_m"])
    _put(out, "tunnel.rays.modal_near.first_window_diff_db", engines.attrs.get("modal_near_first_window_diff_db"))
    _put(out, "tunnel.rays.modal_near.beyond_max_diff_db", engines.attrs.get("modal_near_beyond_max_diff_db"))
    circle = engines.attrs["far_circle_modal_slope_db_per_km"]
    _put(out, "tunnel.rays.circle_modal_slope_db_per_km.1500_5000", circle)
    _put(out, "tunnel.rays.circle_beat_length_m", engines.attrs["far_circle_beat_length_m"])
    _put(out, "tunnel.rays.circle_n_modes", engines.attrs["far_circle_n_modes"])
    _put(out, "tunnel.rays.square_minus_circle_slope_db_per_km", engines.attrs["far_modal_slope_db_per_km"] - circle)
    _put(out, "tunnel.rays.sbr_circle.local_mean_slope_db_per_km", engines.attrs["far_circle_sbr_slope_db_per_km"])
    _put(out, "tunnel.rays.sbr_circle.modal_max_diff_db", engines.attrs["far_circle_sbr_modal_max_diff_db"])
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
        for thr in DELAY_SPREAD_THRESHOLDS_DB:
            v = side_wall_map.get(f"delay_rms_thr{thr:g}_s")
            _put(
                out,
                f"tunnel.sens.slot_side_wall.delay_spread_ns.thr{thr:g}.median",
                None if v is None else np.median(v) * 1e9,
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
    headline: str = "wideband",
    slot_spacing_m: float = 20.0,
) -> dict[str, Any]:
    """The key numbers ``tunnel.*`` (:data:`SPECS`, with the sensitivity cases' keys of
    :func:`sens_spec`) from the study's intermediates, beside the source's design targets.

    Parameters
    ----------
    runs : dict
        (train, setup) -> run of :func:`railradio.tunnel.simulate.run_train`; needs
        ``physical_<headline>`` and ``physical_separable`` for every train of :data:`TRAINS`
        (``hst``'s separable run also gives the CEP and dilutions); the other setups of
        :data:`railradio.tunnel.study.SETUPS` are optional (their keys null when missing).
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
    headline : {'wideband', 'separable'}
        The receiver of the headline keys (``tunnel.<train>.err_m.p95`` ..., the
        availabilities): the config's ``key_measurement``.
    slot_spacing_m : float
        Slot spacing [m]: a track is lost where its error exceeds it (:func:`lost_epochs`).

    Returns
    -------
    dict
        Key name -> JSON entry of :meth:`railradio.keynumbers.KeySpec.entry` (``value`` in
        the key's ``unit``, ``mc_stderr`` where realizations give one, the source's value
        and relation, description, digits).

    Raises
    ------
    ValueError
        When a key's value is not finite, or ``headline`` is not a receiver.
    """
    if headline not in RECEIVERS:
        raise ValueError(f"headline must be one of {RECEIVERS}, got {headline!r}")
    out: dict[str, Any] = {}
    pooled_wb = _run_keys(out, runs, headline, slot_spacing_m)
    _wideband_keys(out, pooled_wb)
    _map_keys(out, maps, tables, engines, coverage_dbm, blind_dbm, min_rays)
    _hst_and_lining_keys(out, runs, wavelength_m, side_m, eps)
    _table_keys(out, tables, engines)
    _sensitivity_keys(out, sens, peak_bias, side_wall_map)
    return out
