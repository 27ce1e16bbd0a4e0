"""Figures of the tunnel study (cheap: read the intermediates)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from railradio.plotting import figure, save

TRAINS = ("metro", "hst", "freight")


def rssi_map(maps: dict[str, xr.Dataset], coverage_dbm: float, blind_dbm: float, pdf, png) -> None:
    """Figure ``tunnel_rssi_map``: the local-mean RSSI along the tunnel of every map (top),
    and a zoom on x = 1000-1100 m of the image map's coherent and local-mean RSSI (bottom);
    coverage threshold dashed, blind-spot level dotted.

    Parameters
    ----------
    maps : dict
        Table name -> map of :func:`railradio.tunnel.study.make_map` (``x_m``,
        ``rssi_mean_dbm``, ``rssi_coherent_dbm``); needs ``image``.
    coverage_dbm : float
        Coverage threshold [dBm].
    blind_dbm : float
        Blind-spot level [dBm].
    pdf : str or os.PathLike
        Output PDF path.
    png : str or os.PathLike
        Output PNG path.

    Returns
    -------
    None
        The figure is written to ``pdf`` and ``png``.
    """
    fig, (ax, az) = figure(nrows=2, figsize=(7.0, 5.6))
    labels = {"image": "physical, image method (square)", "source": "source's model"}
    for name, ds in maps.items():
        ax.plot(ds["x_m"], ds["rssi_mean_dbm"], lw=0.8, label=labels.get(name, name))
    for a in (ax, az):
        a.axhline(coverage_dbm, color="k", ls="--", lw=0.8)
        a.axhline(blind_dbm, color="k", ls=":", lw=0.8)
    ax.set_xlabel("position along the tunnel x [m]")
    ax.set_ylabel("RSSI, local mean [dBm]")
    ax.legend(fontsize=7, loc="lower right")
    ds = maps["image"]
    sel = (ds["x_m"] >= 1000) & (ds["x_m"] <= 1100)
    az.plot(ds["x_m"][sel], ds["rssi_coherent_dbm"][sel], lw=0.6, label="coherent (image)")
    az.plot(ds["x_m"][sel], ds["rssi_mean_dbm"][sel], lw=1.2, label="local mean (image)")
    az.set_xlabel("x [m] (zoom; coverage - - , blind spot ···)")
    az.set_ylabel("RSSI [dBm]")
    az.legend(fontsize=7, loc="lower right")
    save(fig, pdf, png)


def delay_spread(maps: dict[str, xr.Dataset], pdf, png) -> None:
    """Figure ``tunnel_delay_spread``: the RMS delay spread along the tunnel of every map
    (left) and its distribution over the tunnel (right, CDF, logarithmic delay axis), every
    arrival counted (solid) and, for the image map, with the measurement thresholds (25 and
    30 dB below the profile's peak, dashed), beside the range of medians measured in a straight
    tunnel at 6 GHz, antenna-fed (grey band, 5-10 ns; docs/model/tunnel.md §2.3).

    Parameters
    ----------
    maps : dict
        Table name -> map of :func:`railradio.tunnel.study.make_map` (``x_m``, ``delay_rms_s``
        [s], plotted in ns; ``delay_rms_thr<T>_s`` where present).
    pdf : str or os.PathLike
        Output PDF path.
    png : str or os.PathLike
        Output PNG path.

    Returns
    -------
    None
        The figure is written to ``pdf`` and ``png``.
    """
    fig, (ax, ac) = figure(ncols=2, figsize=(7.5, 3.2))
    for name, ds in maps.items():
        v = ds["delay_rms_s"].values * 1e9
        ax.plot(ds["x_m"], v, lw=0.6, label=name)
        s = np.sort(v)
        ac.plot(s, np.arange(1, s.size + 1) / s.size, label=f"{name}, every arrival")
    thr = [k for k in maps.get("image", xr.Dataset()).data_vars if k.startswith("delay_rms_thr")]
    for i, k in enumerate(thr):
        v = maps["image"][k].values * 1e9
        lab = f"image, {k[len('delay_rms_thr') : -2]} dB threshold"
        ax.plot(maps["image"]["x_m"], v, lw=0.6, ls="--", color=f"C{5 + i}", label=lab)
        s = np.sort(v)
        ac.plot(s, np.arange(1, s.size + 1) / s.size, ls="--", color=f"C{5 + i}", label=lab)
    ac.axvspan(5.0, 10.0, color="0.85", zorder=0, label="measured medians, antenna-fed tunnel, 6 GHz")
    ax.set_yscale("log")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("RMS delay spread [ns]")
    ac.set_xlabel("RMS delay spread [ns]")
    ac.set_ylabel("CDF over the tunnel")
    ac.set_xscale("log")
    ac.legend(fontsize=7)
    save(fig, pdf, png)


def gdop(run: xr.Dataset, pdf, png, span_m: float = 200.0) -> None:
    """Figure ``tunnel_gdop``: the head receiver's dilution of precision over ``span_m`` from
    x = 2000 m, the source's 2-D GDOP (source 4.1.1) against the along-track TDOA dilution
    sigma_x / (c sigma_tau) (logarithmic axis).

    Parameters
    ----------
    run : xarray.Dataset
        A run of :func:`railradio.tunnel.simulate.run_train` (the workflow passes the HST,
        physical, separable run) with ``x_rx_true`` [m], ``gdop_source`` and ``gdop_tdoa`` [1].
    pdf : str or os.PathLike
        Output PDF path.
    png : str or os.PathLike
        Output PNG path.
    span_m : float
        Length of the plotted stretch of head-receiver positions [m].

    Returns
    -------
    None
        The figure is written to ``pdf`` and ``png``.
    """
    fig, ax = figure(figsize=(6.4, 3.4))
    x = run["x_rx_true"].values[:, 0]
    sel = (x >= 2000) & (x <= 2000 + span_m)
    ax.plot(x[sel], run["gdop_source"].values[sel, 0], ".", ms=2, label="source's 2-D GDOP (4.1.1)")
    ax.plot(x[sel], run["gdop_tdoa"].values[sel, 0], ".", ms=2, label=r"along-track TDOA: $\sigma_x / c\sigma_\tau$")
    ax.set_yscale("log")
    ax.set_xlabel("head receiver position x [m] (HST run)")
    ax.set_ylabel("dilution of precision")
    ax.legend(fontsize=7)
    save(fig, pdf, png)


def _cdf(ax, v, **kw):
    s = np.sort(np.asarray(v)[np.isfinite(v)])
    ax.plot(s, np.arange(1, s.size + 1) / s.size, **kw)


def position_error_cdf(runs: dict[tuple[str, str], xr.Dataset], pdf, png, headline: str = "wideband") -> None:
    """Figure ``tunnel_position_error_cdf``: one panel per train type, the CDFs of the KF
    train error [m] pooled over the Monte Carlo realizations (logarithmic axis, 2 m and 5 m
    marked): the headline receiver (bold), its head and tail and its rigid-train KF, the wideband cases (low speed,
    velocity-factor tolerance, feed delays), the separable receiver (the source's assumption)
    and its correlated delay errors, the source's channel; the source's 95 % values of the
    train, head and tail as markers at 0.95.  A lost track (error above one slot spacing)
    shows as the curve's plateau below 1 before the kilometre errors.

    Parameters
    ----------
    runs : dict
        (train, setup) -> run of :func:`railradio.tunnel.simulate.run_train`; needs
        ``physical_<headline>`` for every train of :data:`TRAINS`, the other setups of
        :data:`railradio.tunnel.study.SETUPS` optional.
    pdf : str or os.PathLike
        Output PDF path.
    png : str or os.PathLike
        Output PNG path.
    headline : {'wideband', 'separable'}
        The receiver of the headline keys (config ``key_measurement``).

    Returns
    -------
    None
        The figure is written to ``pdf`` and ``png``.
    """
    from railradio.tunnel.key_specs import SOURCE_P95

    other = "separable" if headline == "wideband" else "wideband"
    names = {"wideband": "wideband (one merged CIR)", "separable": "separable (source's assumption)"}
    curves = (
        (f"physical_{other}", "rep_err", f"train, {names[other]}", {"lw": 1.4, "color": "C3"}),
        ("physical_wideband_slow", "rep_err", "train, wideband, low speed", {"ls": "--", "color": "C0"}),
        ("physical_wideband_vf", "rep_err", "train, wideband, velocity factor +1 %", {"ls": "-.", "color": "C1"}),
        ("physical_wideband_feed", "rep_err", "train, wideband, feeds within TAE", {"ls": ":", "color": "C2"}),
        ("physical_separable_slot_bias", "rep_err", "train, separable, per-slot bias", {"ls": (0, (3, 1, 1, 1))}),
        ("source_separable", "rep_err", "train, separable, source's channel", {"ls": (0, (1, 3)), "color": "grey"}),
    )
    fig, axes = figure(ncols=3, figsize=(9.0, 3.6), sharey=True)
    for ax, tr in zip(axes, TRAINS, strict=True):
        ds = runs[(tr, f"physical_{headline}")]
        _cdf(ax, ds["rep_err"].values.ravel(), label=f"train, {names[headline]}", lw=2.2, color="k")
        _cdf(ax, ds["rep_err_head"].values.ravel(), label="head, same", lw=0.8, color="0.45")
        _cdf(ax, ds["rep_err_tail"].values.ravel(), label="tail, same", lw=0.8, color="0.45", ls="--")
        if "rep_err_rigid" in ds:
            _cdf(ax, ds["rep_err_rigid"].values.ravel(), label="rigid train (all receivers), same", lw=1.4, color="C4")
        for setup, var, lab, kw in curves:
            if (tr, setup) in runs:
                _cdf(ax, runs[(tr, setup)][var].values.ravel(), label=lab, **kw)
        tot, head, tail = SOURCE_P95[tr]
        ax.plot([tot], [0.95], "k*", ms=8, label="source's 95 % value: train")
        ax.plot([head, tail], [0.95, 0.95], "kv", ms=5, mfc="none", label="source's 95 %: head, tail")
        ax.set_xscale("log")
        ax.set_xlim(1e-2, 1e3)
        ax.set_xlabel("KF error [m] (all realizations)")
        ax.set_title(f"{tr} ({ds.attrs['length_m']:g} m, {ds.attrs['speed_kmh']:g} km/h)", fontsize=8)
        for lim in (2.0, 5.0):
            ax.axvline(lim, color="k", lw=0.5, ls=":")
    axes[0].set_ylabel("CDF")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=4, fontsize=6, frameon=False)
    save(fig, pdf, png)


def ray_engines(eng: xr.Dataset, pdf, png) -> None:
    """Figure ``tunnel_ray_engines``: one slot's path gain over the along-axis offset for
    every engine model in the square (sum of ray powers; the image method's coherent gain in
    grey, top), the SBR engines in the square minus the image method (middle) [dB], and one
    slot's far field averaged over beat-length windows (bottom) [dB]: the image method and
    the modal sum in the square, the modal sum in the circle, and the retired SBR engine in
    the circle.

    Parameters
    ----------
    eng : xarray.Dataset
        The engine checks of :func:`railradio.tunnel.engine_checks.make_engines`
        (``power_mean_db``, ``power_coherent_db`` [model, offset_m] [dB]; ``far_local_mean_db``
        [far_order, centre_m], ``modal_local_mean_db`` [centre_m], ``circle_modal_local_mean_db``,
        ``circle_sbr_local_mean_db`` [circle_centre_m] [dB]).
    pdf : str or os.PathLike
        Output PDF path.
    png : str or os.PathLike
        Output PNG path.

    Returns
    -------
    None
        The figure is written to ``pdf`` and ``png``.
    """
    fig, (ax, ad, af) = figure(nrows=3, figsize=(6.4, 7.6), layout="constrained")
    off = eng["offset_m"].values
    for m in eng["model"].values:
        ax.plot(off, eng["power_mean_db"].sel(model=m), label=f"{m} (sum of ray powers)")
    ax.plot(off, eng["power_coherent_db"].sel(model="image_rect"), lw=0.5, color="grey", label="image_rect (coherent)")
    ref = eng["power_mean_db"].sel(model="image_rect")
    for m in ("sbr_rect", "sbr_rect_vector"):
        ad.plot(off, eng["power_mean_db"].sel(model=m) - ref, label=f"{m} - image (sum of ray powers)")
    ad.plot(
        off,
        eng["power_coherent_db"].sel(model="sbr_rect") - eng["power_coherent_db"].sel(model="image_rect"),
        lw=0.6,
        label="sbr_rect - image (coherent)",
    )
    for a in (ax, ad):
        a.set_xscale("log")
    ax.set_ylabel("path gain of one slot [dB]")
    ax.legend(fontsize=6)
    ad.set_xlabel("offset along the tunnel [m]")
    ad.set_ylabel("difference [dB]")
    ad.legend(fontsize=6)
    c, cc = eng["centre_m"].values / 1e3, eng["circle_centre_m"].values / 1e3
    af.plot(c, eng["far_local_mean_db"].isel(far_order=-1), label="square, image method")
    af.plot(c, eng["modal_local_mean_db"], ls="--", label="square, modal sum (EH_mn)")
    af.plot(cc, eng["circle_modal_local_mean_db"], label="circle, modal sum (Marcatili-Schmeltzer)")
    af.plot(cc, eng["circle_sbr_local_mean_db"], lw=0.7, color="grey", label="circle, SBR (retired)")
    af.set_xlabel("offset from the slot [km] (window means over one EH11-EH12 beat length)")
    af.set_ylabel("local mean of one slot [dB]")
    af.legend(fontsize=6)
    save(fig, pdf, png)


def source_vs_physical(
    tables: dict[str, xr.Dataset],
    maps: dict[str, xr.Dataset],
    h_m: float,
    coupling_db: float,
    coverage_dbm: float,
    pdf,
    png,
) -> None:
    """Figure ``tunnel_source_vs_physical``: one slot's local-mean gain relative to the cable
    power over the offset for every table, beside the coupling loss alone (left), and the
    distribution of the local-mean RSSI over the tunnel for every map with the coverage
    threshold (right).

    Parameters
    ----------
    tables : dict
        Table name -> table of :func:`railradio.tunnel.study.make_table` (``offset_m`` [m],
        ``power_mean`` [1]); needs ``image``.
    maps : dict
        Table name -> map of :func:`railradio.tunnel.study.make_map` (``rssi_mean_dbm`` [dBm]).
    h_m : float
        Distance between slot line and receiver in the cross-section [m] (the coupling-loss
        curve's distance is sqrt(offset^2 + h_m^2)).
    coupling_db : float
        Coupling loss L_c at 1 m from the cable [dB].
    coverage_dbm : float
        Coverage threshold [dBm].
    pdf : str or os.PathLike
        Output PDF path.
    png : str or os.PathLike
        Output PNG path.

    Returns
    -------
    None
        The figure is written to ``pdf`` and ``png``.
    """
    fig, (ax, ac) = figure(ncols=2, figsize=(8.0, 3.4))
    labels = {"image": "physical (image, square)", "source": "source's model"}
    for name, t in tables.items():
        off = t["offset_m"].values
        sel = off >= 0.5
        ax.plot(off[sel], 10 * np.log10(t["power_mean"].values[sel]), label=labels.get(name, name))
    off = tables["image"]["offset_m"].values
    sel = off >= 0.5
    ax.plot(
        off[sel],
        -(coupling_db + 10 * np.log10(np.hypot(off[sel], h_m))),
        "k--",
        lw=0.8,
        label="coupling loss alone (85 + 10 lg d)",
    )
    ax.set_xscale("log")
    ax.set_xlabel("offset from the slot [m]")
    ax.set_ylabel("gain re cable power [dB]")
    ax.legend(fontsize=6)
    for name, m in maps.items():
        _cdf(ac, m["rssi_mean_dbm"].values, label=labels.get(name, name))
    ac.axvline(coverage_dbm, color="k", ls="--", lw=0.8)
    ac.set_xlabel("RSSI, local mean [dBm]")
    ac.set_ylabel("CDF over the tunnel")
    save(fig, pdf, png)


def sensitivity(sens: dict[str, xr.Dataset], shadow_sigma_db, delay_sigma_ns, delay_errors, pdf, png) -> None:
    """95th-percentile KF train error against the shadowing sigma and the delay-error sigma
    (one train type per colour), the delay sweep with each delay-error model (line style);
    error bars: Monte Carlo standard error over the realizations.

    Parameters
    ----------
    sens : dict
        Train type -> sensitivity cases of :func:`railradio.tunnel.sensitivity.make_sensitivity`
        (``err_p95_m`` [case] and ``rep_err_p95_m`` [case, realization] [m]).
    shadow_sigma_db : sequence of float
        The swept shadowing sigmas [dB] (``sensitivity.shadow_sigma_db``, naming the cases).
    delay_sigma_ns : sequence of float
        The swept delay-error sigmas [ns] (``sensitivity.delay_sigma_ns``).
    delay_errors : sequence of str
        The delay-error models (``white``, ``ar1``, ``slot_bias``; ``sensitivity.delay_errors``).
    pdf : str or os.PathLike
        Output PDF path.
    png : str or os.PathLike
        Output PNG path.

    Returns
    -------
    None
        The figure is written to ``pdf`` and ``png``.
    """
    from railradio.tunnel.sensitivity import case_label

    fig, (a_s, a_d) = figure(ncols=2, figsize=(7.5, 3.2))
    styles = {"white": "-", "ar1": "--", "slot_bias": ":"}
    names = {"white": "white", "ar1": "AR(1)", "slot_bias": "per-slot bias"}

    def curve(ds, labels):
        cases = list(ds["case"].values)
        i = [cases.index(c) for c in labels]
        per = ds["rep_err_p95_m"].values[i]
        se = per.std(axis=1, ddof=1) / np.sqrt(per.shape[1]) if per.shape[1] > 1 else None
        return ds["err_p95_m"].values[i], se

    for c, tr in enumerate(t for t in TRAINS if t in sens):
        ds = sens[tr]
        y, se = curve(ds, [f"shadow_sigma_db_{case_label(v)}" for v in shadow_sigma_db])
        a_s.errorbar(shadow_sigma_db, y, yerr=se, color=f"C{c}", marker="o", ms=3, capsize=2, label=tr)
        for e in delay_errors:
            suffix = "" if e == "white" else f"_{e}"
            y, se = curve(ds, [f"delay_sigma_ns_{case_label(v)}{suffix}" for v in delay_sigma_ns])
            a_d.errorbar(
                delay_sigma_ns,
                y,
                yerr=se,
                color=f"C{c}",
                ls=styles.get(e, "-."),
                marker="o",
                ms=3,
                capsize=2,
                label=f"{tr}, {names.get(e, e)}",
            )
    a_s.set_xlabel("shadowing sigma [dB] (delay error white)")
    a_d.set_xlabel("delay-error sigma [ns]")
    for a in (a_s, a_d):
        a.set_ylabel("train error, 95th pct [m]")
        a.set_ylim(bottom=0)
    a_s.legend(fontsize=7)
    a_d.legend(fontsize=6, ncol=1)
    save(fig, pdf, png)
