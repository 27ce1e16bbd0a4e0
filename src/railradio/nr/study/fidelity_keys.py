"""The fidelity target's key numbers: ``nr.fidelity.*`` (every shortcut's changed
decisions, error distributions and verdict) and ``nr.detector.*`` (the false-alarm rates
and our detector's constants one at a time)."""

from __future__ import annotations

import numpy as np

from railradio.nr.study.fidelity import DECISIONS, Comparison
from railradio.nr.study.fidelity_stats import bounded, within_share

DECISION_LABEL = {
    "detection": "SS-block detection",
    "selection": "selected cells",
    "toa": "TOA (> 1 full-rate sample)",
    "aod": "AOD (> 0.1 deg)",
}
COMPARISON_LABEL = {
    "search": "the decimated coarse-to-fine search against every full-rate lag",
    "band": "the band-limited synthesis (with nr.channel.band_edges, plus its edges) against the full band",
    "form": "each tap's symbols wrapped within their extent against the taps' spill kept",
    "spill": "each tap's symbols wrapped within their extent against the taps' spill kept, at the production's rate",
    "taps": "Rayleigh taps held per symbol against per sample",
    "geometry": "the geometry held over the burst against the train's motion",
    "far_taps": "far interferers as one non-fading tap against fully fading",
    "noise": "a redraw of the noise (decimated against full-rate, projected)",
    "all": "the production path against the exact computation",
}

FORM_EXACT_SPILL_LABEL = "the fast path's per-symbol taps with the exact spill against every tap's own delayed extent"
"""The ``form`` comparison's label when the production computes the spill exactly
(``nr.channel.exact_spill``): it then checks the exact spill at the full band."""


def key_numbers(summary: dict, comps: dict[str, Comparison], n_epochs: int, seconds: dict[str, float]) -> dict:
    """Key numbers ``nr.fidelity.*`` from :func:`railradio.nr.study.fidelity_stats.summarize`'s output.

    Parameters
    ----------
    summary : dict
        :func:`railradio.nr.study.fidelity_stats.summarize`'s output.
    comps : dict of str to Comparison
        The comparisons measured (:func:`railradio.nr.study.fidelity.comparisons`).
    n_epochs : int
        Epochs on which every shortcut was measured.
    seconds : dict of str to float
        Path -> mean computing time per epoch, s.

    Returns
    -------
    dict of str to dict
        Key name -> its JSON entry (:meth:`railradio.keynumbers.KeySpec.entry`).
    """
    from railradio.keynumbers import KeySpec

    out = {}

    def put(name, unit, desc, value, digits=3):
        out[name] = KeySpec(name, unit, desc, digits=digits).entry(
            None if value is None or not np.isfinite(value) else float(value)
        )

    put("nr.fidelity.n_epochs", "1", "paper-scale epochs on which every shortcut was measured", n_epochs)
    for v, sec in seconds.items():
        put(
            f"nr.fidelity.cost_s.{v}",
            "s",
            f"mean time per epoch of the '{v}' path (synthesis and correlation, one core)",
            sec,
        )
    label = dict(COMPARISON_LABEL)
    if "spill" in comps and not comps["spill"].taken:  # the production computes the spill exactly
        label["form"] = FORM_EXACT_SPILL_LABEL
    all_ok = True
    for c, per in summary.items():
        comp = comps[c]
        c_ok = True
        for r, m in per.items():
            taken = "" if comp.taken else " (a shortcut the production does not take)"
            where = f"{label[c]}{taken}, receiver {r}"
            for k in DECISIONS:
                base = f"nr.fidelity.{c}.{r}.{k}_change_frac"
                put(base, "1", f"share of changed decisions: {DECISION_LABEL[k]} ({where})", m[k]["frac"])
                put(base + ".lo", "1", f"lower end of the 95 % interval (epoch-clustered Wilson) of {base}", m[k]["lo"])
                put(base + ".hi", "1", f"upper end of the 95 % interval (epoch-clustered Wilson) of {base}", m[k]["hi"])
                put(f"nr.fidelity.{c}.{r}.{k}_n", "1", f"decisions compared: {DECISION_LABEL[k]} ({where})", m[k]["n"])
            put(
                f"nr.fidelity.{c}.{r}.toa_ks_p",
                "1",
                f"two-sample KS p-value of the TOA range errors ({where})",
                m["toa_ks_p"],
            )
            put(
                f"nr.fidelity.{c}.{r}.aod_ks_p",
                "1",
                f"two-sample KS p-value of the AOD errors ({where})",
                m["aod_ks_p"],
            )
            d = f"nr.fidelity.{c}.{r}.within5m_diff"
            put(
                d,
                "1",
                f"difference of the share of candidates with a TOA within 5 m, shortcut off minus on ({where})",
                m["within5_diff"],
            )
            put(d + ".lo", "1", f"lower end of the 95 % epoch-bootstrap interval of {d}", m["within5_diff_lo"])
            put(d + ".hi", "1", f"upper end of the 95 % epoch-bootstrap interval of {d}", m["within5_diff_hi"])
            ok = bounded(m, summary["noise"][r], comp.stochastic)
            put(
                f"nr.fidelity.{c}.{r}.bounded",
                "1",
                f"1: bounded by the rule of railradio.nr.study.fidelity_stats.bounded, 0: not ({where})",
                float(ok),
            )
            c_ok &= ok
        put(f"nr.fidelity.{c}.bounded", "1", f"1: {label[c]}{taken} bounded for every receiver, 0: not", float(c_ok))
        all_ok &= c_ok or not comp.taken
    put(
        "nr.fidelity.all_bounded",
        "1",
        "1: every comparison of a shortcut the production takes bounded for every receiver, 0: not",
        float(all_ok),
    )
    ks = [m[k] for per in summary.values() for m in per.values() for k in ("toa_ks_p", "aod_ks_p") if np.isfinite(m[k])]
    put(
        "nr.fidelity.min_ks_p",
        "1",
        "smallest two-sample KS p-value of the TOA and AOD errors over every comparison and receiver",
        min(ks) if ks else None,
    )
    return out


def detector_key_numbers(ds, noise_fa: dict[str, tuple[int, int]]) -> dict:
    """Key numbers ``nr.detector.*``: the false-alarm rates per block on noise-only bursts and
    on interference-only bursts (the anchor silent), and our detector's constants one at a
    time (the TOA-within-5-m share and the detected blocks per candidate in range).

    Parameters
    ----------
    ds : xarray.Dataset
        The fidelity dataset (:func:`railradio.nr.study.fidelity_dataset.to_dataset`).
    noise_fa : dict of str to tuple of (int, int)
        Receiver -> (false alarms, block tests) on noise-only bursts
        (:func:`railradio.nr.study.fidelity_detector.noise_false_alarms`).

    Returns
    -------
    dict of str to dict
        Key name -> its JSON entry (:meth:`railradio.keynumbers.KeySpec.entry`).
    """
    from railradio.keynumbers import KeySpec
    from railradio.stats import clustered_rate, wilson_interval

    out = {}

    def put(name, unit, desc, value):
        out[name] = KeySpec(name, unit, desc).entry(None if value is None or not np.isfinite(value) else float(value))

    n_blocks = ds.sizes["block"]
    for r, (k, n) in noise_fa.items():
        lo, hi = wilson_interval(k, n)
        put(f"nr.detector.{r}.pfa_noise", "1", f"false alarms per block test on noise-only bursts, receiver {r}", k / n)
        put(f"nr.detector.{r}.pfa_noise.lo", "1", "lower end of its 95 % Wilson interval", float(lo))
        put(f"nr.detector.{r}.pfa_noise.hi", "1", "upper end of its 95 % Wilson interval", float(hi))
        put(f"nr.detector.{r}.pfa_noise_n", "1", "block tests on noise-only bursts", n)
    for r in ds["receiver"].values:
        fa = ds["fa_interference"].sel(receiver=r).values.astype(float)
        ev = np.zeros((fa.size, n_blocks))
        for i, f in enumerate(fa):
            ev[i, : int(f)] = 1.0
        rate = clustered_rate(ev)
        put(
            f"nr.detector.{r}.pfa_interference",
            "1",
            f"blocks detected per block test for the anchor cell's PCI with the anchor silent (receiver {r})",
            rate["p"],
        )
        put(
            f"nr.detector.{r}.pfa_interference.lo",
            "1",
            "lower end of its 95 % epoch-clustered Wilson interval",
            rate["lo"],
        )
        put(
            f"nr.detector.{r}.pfa_interference.hi",
            "1",
            "upper end of its 95 % epoch-clustered Wilson interval",
            rate["hi"],
        )
    inr = ds["in_range"].values.astype(bool)
    d3d = ds["d3d"].values
    prod = ds.sel(path="production", receiver="robust")
    rows = {"default": (prod["toa"].values, prod["detected"].values.sum(axis=-1))}
    for s in ds["setting"].values:
        rows[str(s)] = (ds["det_toa"].sel(setting=s).values, ds["det_n_detected"].sel(setting=s).values)
    for label, (toa, n_det) in rows.items():
        put(
            f"nr.detector.robust.sens.{label}.within5m",
            "1",
            f"share of in-range candidates with a TOA within 5 m, our receiver ({label})",
            float(np.nanmean(within_share(toa, d3d, inr))),
        )
        put(
            f"nr.detector.robust.sens.{label}.detected_blocks",
            "1",
            f"mean detected blocks per in-range candidate, our receiver ({label})",
            float(np.mean(n_det[inr])),
        )
    return out
