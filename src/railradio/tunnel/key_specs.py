"""The tunnel study's key numbers named and described: every key's unit, description and the
source's value (source 003 §8) where it gives one (docs/model/tunnel.md).
"""

from __future__ import annotations

from railradio.keynumbers import KeySpec

TRAINS = ("metro", "hst", "freight")
ENGINE_TOL_MEAN_DB = 0.05
ENGINE_TOL_COHERENT_DB = 0.3
"""|SBR - image| bounds of the cross-validation test in the square tunnel (local mean, coherent) [dB]."""
DELAY_SPREAD_THRESHOLDS_DB = (25.0, 30.0)
"""Dynamic ranges of the thresholded delay-spread keys [dB] (the measurement campaigns' convention)."""
SOURCE_P95 = {"metro": (1.5, 1.2, 1.8), "hst": (2.0, 1.5, 2.5), "freight": (3.5, 2.0, 5.0)}
"""source 003 §8.1: 95 % accuracy of the train, its head and its tail [m] (stated as ±)."""


def _add(s: dict[str, KeySpec], name, unit, desc, src=None, rel=None, digits=3) -> None:
    s[name] = KeySpec(name, unit, desc, src, rel, digits)


def _train_specs(s: dict[str, KeySpec]) -> None:
    """Per train type: the accuracy of the headline receiver (``key_measurement``, by default
    the wideband one), of both receivers, of the wideband cases and the separable variants
    (source 8.1)."""
    hl = "the headline receiver (config key_measurement; wideband by default)"
    for tr in TRAINS:
        tot, head, tail = SOURCE_P95[tr]
        _add(
            s,
            f"tunnel.{tr}.err_m.p95",
            "m",
            f"{tr}: 95th pct of the train error sqrt((e_h^2+e_t^2)/2), KF, {hl}, pooled over the realizations",
            tot,
            "=",
        )
        _add(s, f"tunnel.{tr}.head_err_m.p95", "m", f"{tr}: 95th pct of the head error, KF, {hl}", head, "=")
        _add(s, f"tunnel.{tr}.tail_err_m.p95", "m", f"{tr}: 95th pct of the tail error, KF, {hl}", tail, "=")
        _add(
            s,
            f"tunnel.{tr}.wideband.err_m.p95",
            "m",
            f"{tr}: 95th pct of the train error, KF, wideband receiver (one merged CIR; errors from the channel)",
        )
        _add(
            s,
            f"tunnel.{tr}.separable.err_m.p95",
            "m",
            f"{tr}: the same, separable receiver (the source's assumption: every slot's delay measured on "
            "its own, 20 ns errors white in time [ours: the source gives no time structure])",
        )
        _add(
            s,
            f"tunnel.{tr}.ar1.err_m.p95",
            "m",
            f"{tr}: separable receiver with an AR(1) delay error along the track "
            "(measurement.delay_corr_m), same sigma",
        )
        _add(
            s,
            f"tunnel.{tr}.slot_bias.err_m.p95",
            "m",
            f"{tr}: separable receiver with one constant delay bias per slot "
            "(the source's systematic per-slot errors), same sigma",
        )
        _add(
            s,
            f"tunnel.{tr}.rigid.err_m.p95",
            "m",
            f"{tr}: 95th pct, rigid-train KF on all receivers, {hl} "
            "(pooled over the realizations where they are run: wideband)",
        )
        _add(s, f"tunnel.{tr}.pf.err_m.p95", "m", f"{tr}: 95th pct, particle filter, {hl}")
        _add(s, f"tunnel.{tr}.snapshot.err_m.p95", "m", f"{tr}: 95th pct of the head receiver's snapshot error, {hl}")
        _add(
            s,
            f"tunnel.{tr}.rssi.err_m.p95",
            "m",
            f"{tr}: 95th pct of the head receiver's RSSI-ranging LS error (separable receiver)",
        )
        _add(
            s,
            f"tunnel.{tr}.source_channel.err_m.p95",
            "m",
            f"{tr}: 95th pct of the train error, KF, separable receiver, the source's channel",
        )
        _add(
            s,
            f"tunnel.{tr}.length_err_m.p95",
            "m",
            f"{tr}: 95th pct of |estimated head-tail distance - train length|, KF, {hl} (the observable "
            "part of the attitude: with collinear slots the lateral offset, hence the source's "
            "attitude angle, is not observable)",
        )


def _loss_specs(s: dict[str, KeySpec]) -> None:
    """Per train type: the wideband cases' accuracy; per receiver and case the lost share, the
    time to loss, the kept epochs' accuracy."""
    hl = "the headline receiver (config key_measurement; wideband by default)"
    for tr in TRAINS:
        _add(
            s,
            f"tunnel.{tr}.wideband_slow.err_m.p95",
            "m",
            f"{tr}: wideband receiver at the low speed (cases.low_speed_kmh) instead of cruise",
        )
        _add(
            s,
            f"tunnel.{tr}.wideband_vf.err_m.p95",
            "m",
            f"{tr}: wideband receiver whose velocity factor is off by the cable's tolerance "
            "(cases.velocity_factor_rel)",
        )
        _add(
            s,
            f"tunnel.{tr}.wideband_feed.err_m.p95",
            "m",
            f"{tr}: wideband receiver whose feeds' delays are known only to the time-alignment bound "
            "(cases.feed_delay_max_ns)",
        )
        for pre, who in (
            ("", hl),
            (".wideband", "wideband receiver"),
            (".separable", "separable receiver"),
            (".wideband_slow", "wideband receiver, low speed"),
            (".wideband_vf", "wideband receiver, velocity-factor tolerance"),
            (".wideband_feed", "wideband receiver, feed delays within the time-alignment bound"),
        ):
            _add(
                s,
                f"tunnel.{tr}{pre}.lost_frac",
                "1",
                f"{tr}: share of the KF's train-error epochs (all realizations) lost, error above one slot "
                f"spacing, {who}",
                digits=4,
            )
            _add(
                s,
                f"tunnel.{tr}{pre}.time_to_loss_s",
                "s",
                f"{tr}: mean over the realizations that lose the track of the time of their first lost epoch, {who}",
                digits=1,
            )
            _add(
                s,
                f"tunnel.{tr}{pre}.tracked.err_m.p95",
                "m",
                f"{tr}: 95th pct of the KF train error over the epochs not lost, {who}",
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
    _add(s, "tunnel.coverage_frac.source_model", "1", "same, the source's propagation model")
    _add(s, "tunnel.blind_spot_frac", "1", "share of the tunnel in a blind spot (source 5.1.2), physical")
    _add(s, "tunnel.blind_spot_frac.source_model", "1", "share in a blind spot, the source's model")
    for lim, src in ((5, 0.95), (2, 0.85)):
        _add(
            s,
            f"tunnel.availability.err_lt_{lim}m",
            "1",
            f"share of epochs with train error < {lim} m (KF, all trains and realizations, the headline receiver)",
            src,
            "≥",
        )
        for rec in ("wideband", "separable"):
            _add(s, f"tunnel.availability.{rec}.err_lt_{lim}m", "1", f"same, < {lim} m, {rec} receiver")
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
    _add(s, "tunnel.delay_spread_ns.median.source_model", "ns", "median RMS delay spread, the source's model")
    for thr in DELAY_SPREAD_THRESHOLDS_DB:
        t = f"{thr:g}"
        _add(
            s,
            f"tunnel.delay_spread_ns.thr{t}.median",
            "ns",
            f"median RMS delay spread along the tunnel with the arrivals more than {t} dB below the "
            "local-mean profile's peak dropped (a measurement's dynamic range; physical, image)",
        )
        _add(s, f"tunnel.delay_spread_ns.thr{t}.p90", "ns", f"90th pct of the same ({t} dB threshold)")
        _add(
            s,
            f"tunnel.delay_spread_ns.thr{t}.median.source_model",
            "ns",
            f"median RMS delay spread, {t} dB threshold, the source's model",
        )
        _add(
            s,
            f"tunnel.sens.slot_side_wall.delay_spread_ns.thr{t}.median",
            "ns",
            f"median RMS delay spread, {t} dB threshold, cable on the side wall",
        )
    _add(s, "tunnel.rssi_dbm.median", "dBm", "median local-mean RSSI (physical, image)")
    _add(s, "tunnel.rssi_dbm.median.source_model", "dBm", "median local-mean RSSI, the source's model")
    _add(s, "tunnel.rays.order", "1", "reflection order chosen by the convergence criterion")
    _add(s, "tunnel.rays.families_image", "1", "image-method rays (families) per slot")
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
    _add(s, "tunnel.hst.cep_m", "m", "HST: CEP = 0.59 sigma_x (source 4.3.2) of the TDOA snapshot, sigma_y = 0")
    _add(
        s,
        "tunnel.hst.separable.snapshot.err_m.p95",
        "m",
        "95th pct of the HST head receiver's separable TDOA snapshot error",
    )
    _add(
        s,
        "tunnel.hst.separable.snapshot.err_m.p50",
        "m",
        "HST: median separable TDOA snapshot error (the CEP's empirical counterpart)",
    )
    _add(s, "tunnel.hst.gdop_source.median", "1", "HST head receiver: median of the source's 2-D GDOP")
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
        "rays.far_decay_m, image method at rays.max_order (test: within 0.15 dB/km of the EH_mn modal sum's)",
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
    _circle_specs(s)
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


def _circle_specs(s: dict[str, KeySpec]) -> None:
    """The circle's modal far field, where the square's modes part from its rays, the retired SBR engine."""
    _add(
        s,
        "tunnel.rays.circle_modal_slope_db_per_km.1500_5000",
        "dB/km",
        "the circle's far field: one slot's local mean from the lossy modes of the circular guide (Marcatili & "
        "Schmeltzer 1964), averaged over one EH11-EH12 beat length, its decay over rays.far_decay_m",
        digits=2,
    )
    _add(
        s,
        "tunnel.rays.modal_near.first_window_diff_db",
        "dB",
        "the square's modal sum against the image method near the slot: |difference| of one slot's local mean "
        "(40 wavelengths) in the window at the slot, where steep rays break the modes' grazing losses",
        digits=1,
    )
    _add(
        s,
        "tunnel.rays.modal_near.beyond_max_diff_db",
        "dB",
        "the same, the largest |difference| of the later local-mean windows to 600 m",
        digits=1,
    )
    _add(s, "tunnel.rays.circle_beat_length_m", "m", "EH11-EH12 beat length of the circular tunnel", digits=0)
    _add(s, "tunnel.rays.circle_n_modes", "1", "modes of the circular guide carrying the slot's field to the receiver")
    _add(
        s,
        "tunnel.rays.square_minus_circle_slope_db_per_km",
        "dB/km",
        "how much faster one slot's far field decays in the square of equal area (the positioning engine's "
        "cross-section) than in the true circle: the two modal sums' slopes over rays.far_decay_m",
        digits=2,
    )
    _add(
        s,
        "tunnel.rays.sbr_circle.local_mean_slope_db_per_km",
        "dB/km",
        "the retired circular SBR engine: the same far decay (not used by any other number)",
        digits=2,
    )
    _add(
        s,
        "tunnel.rays.sbr_circle.modal_max_diff_db",
        "dB",
        "the retired circular SBR engine: largest difference of its beat-length window means from the modal sum's "
        "over rays.far_decay_m",
        digits=1,
    )


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


def _modal_specs(s: dict[str, KeySpec]) -> None:
    """The square's modal-sum reference of the ray engine's far field."""
    _add(
        s,
        "tunnel.rays.modal_slope_db_per_km.1500_5000",
        "dB/km",
        "the same decay of the lossy EH_mn modal sum for this slot and receiver (Emslie, Lagace & Strong 1975; "
        "every propagating mode), the ray engine's far-field reference",
        digits=2,
    )
    _add(
        s,
        "tunnel.rays.modal_max_diff_db",
        "dB",
        "largest |image method - modal sum| of those beat-length window means (1.5-5 km)",
        digits=2,
    )


def _specs() -> dict[str, KeySpec]:
    s: dict[str, KeySpec] = {}
    _train_specs(s)
    _loss_specs(s)
    _coverage_specs(s)
    _channel_specs(s)
    _ray_check_specs(s)
    _modal_specs(s)
    _delay_error_and_guide_specs(s)
    _peak_bias_and_side_wall_specs(s)
    return s


SPECS = _specs()


def sens_spec(case: str, train: str) -> KeySpec:
    """Key of one sensitivity case and train type (names follow the config's cases).

    Parameters
    ----------
    case : str
        Sensitivity case label (:func:`railradio.tunnel.sensitivity.sensitivity_cases`, or
        ``slot_side_wall``).
    train : str
        Train type (``metro``, ``hst``, ``freight``).

    Returns
    -------
    KeySpec
        The key ``tunnel.sens.<case>.<train>.err_m.p95`` [m]: the 95th percentile of the KF
        train error, pooled over realizations.
    """
    return KeySpec(
        f"tunnel.sens.{case}.{train}.err_m.p95",
        "m",
        f"{train}: 95th pct of the train error, KF, sensitivity case {case} (pooled over realizations)",
    )
