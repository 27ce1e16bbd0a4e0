"""The fidelity target's measures and verdicts: the changed decisions between two paths,
the error distributions' comparison (two-sample KS, the TOA-within-5-m share with a paired
epoch bootstrap) and the rule by which a shortcut is bounded."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.channel.antenna import wrap_rad
from railradio.nr.study.fidelity import AOD_CHANGE_DEG, COMPARISONS, DECISIONS, TOA_CHANGE_SAMPLES, Comparison
from railradio.nr.waveform.numerology import SAMPLE_RATE_HZ


def toa_error_m(toa_samples: NDArray, d3d_m: NDArray) -> NDArray[np.float64]:
    """TOA range error [m] (NaN where nothing was detected).

    Parameters
    ----------
    toa_samples : numpy.ndarray
        TOA estimates [full-rate samples] (NaN: nothing detected), e.g. [E, C].
    d3d_m : numpy.ndarray
        True 3-D train-RRH distances [m], same shape.

    Returns
    -------
    numpy.ndarray
        toa_samples / F_s · c - d3d_m [m], same shape.
    """
    return toa_samples / SAMPLE_RATE_HZ * SPEED_OF_LIGHT_M_S - d3d_m


def aod_error_deg(aod_rad: NDArray, aod_true_rad: NDArray) -> NDArray[np.float64]:
    """AOD error [deg], wrapped to (-180, 180].

    Parameters
    ----------
    aod_rad : numpy.ndarray
        AOD estimates [rad] (NaN: nothing detected), e.g. [E, C].
    aod_true_rad : numpy.ndarray
        True AODs [rad], same shape.

    Returns
    -------
    numpy.ndarray
        The wrapped difference aod_rad - aod_true_rad [deg], same shape.
    """
    return np.degrees(wrap_rad(aod_rad - aod_true_rad))


def changed(kind: str, a: dict[str, NDArray], b: dict[str, NDArray]) -> NDArray[np.float64]:
    """Per-decision change indicators of decision ``kind`` between two runs' arrays
    (``detected`` [E, C, B], ``selected``/``toa``/``aod`` [E, C]): 1 changed, 0 not, NaN
    where neither run made that decision (no TOA/AOD in either). Returns [E, n].

    Parameters
    ----------
    kind : str
        ``"detection"``, ``"selection"``, ``"toa"`` or ``"aod"`` (any other value is taken as
        ``"aod"``). A TOA changes by more than :data:`railradio.nr.study.fidelity.TOA_CHANGE_SAMPLES`,
        an AOD by more than :data:`railradio.nr.study.fidelity.AOD_CHANGE_DEG`, or it exists in one run only.
    a, b : dict of str to numpy.ndarray
        The two runs' arrays (one receiver's entry of :func:`stack`): ``detected`` (bool) [E, C, B],
        ``selected`` (bool) [E, C], ``toa`` [full-rate samples] [E, C], ``aod`` [rad] [E, C].

    Returns
    -------
    numpy.ndarray
        [E, C·B] for ``"detection"``, else [E, C]: 1.0 changed, 0.0 not, NaN no decision (TOA, AOD).
    """
    if kind == "detection":
        out = (a["detected"] != b["detected"]).astype(float)
        return out.reshape(out.shape[0], -1)
    if kind == "selection":
        return (a["selected"] != b["selected"]).astype(float)
    key, tol = ("toa", TOA_CHANGE_SAMPLES) if kind == "toa" else ("aod", np.radians(AOD_CHANGE_DEG))
    x, y = a[key], b[key]
    fa, fb = np.isfinite(x), np.isfinite(y)
    with np.errstate(invalid="ignore"):
        diff = np.abs(wrap_rad(x - y)) if key == "aod" else np.abs(x - y)
        out = np.where(fa & fb, (diff > tol + 1e-9).astype(float), np.where(fa | fb, 1.0, np.nan))
    return out


def stack(epochs: list[dict], receivers: list[str]) -> dict:
    """The per-epoch results of :meth:`railradio.nr.study.fidelity.FidelityRun.epoch` as arrays:
    ``{path: {receiver: {"detected" [E, C, B], "selected", "toa", "aod" [E, C]}}}``.

    Parameters
    ----------
    epochs : list of dict
        E results of :meth:`railradio.nr.study.fidelity.FidelityRun.epoch` (same paths, receivers
        and candidate count).
    receivers : list of str
        Receiver names.

    Returns
    -------
    dict
        Path -> receiver -> ``detected`` (bool) [E, C, B], ``selected`` (bool) [E, C],
        ``toa`` [full-rate samples] [E, C], ``aod`` [rad] [E, C].
    """
    out = {}
    for v in epochs[0]["decisions"]:
        out[v] = {}
        for r in receivers:
            ds = [e["decisions"][v][r] for e in epochs]
            out[v][r] = {
                "detected": np.stack([d.detected for d in ds]),
                "selected": np.stack([d.selected for d in ds]),
                "toa": np.stack([d.toa_samples for d in ds]),
                "aod": np.stack([d.aod_rad for d in ds]),
            }
    return out


TOA_WITHIN_M = 5.0
"""The TOA-within share's range-error limit [m]."""
GOAL_CHANGE_FRAC = 0.005
"""A deterministic shortcut is bounded when each changed-decision share is at most this."""


def within_share(toa: NDArray, d3d_m: NDArray, in_range: NDArray) -> NDArray[np.float64]:
    """[E, C] 1 where the TOA range error is within :data:`TOA_WITHIN_M`, 0 where not (no
    TOA counts as not), NaN for candidates out of range (they send nothing).

    Parameters
    ----------
    toa : numpy.ndarray
        TOA estimates [full-rate samples] (NaN: nothing detected), [E, C].
    d3d_m : numpy.ndarray
        True 3-D distances [m], [E, C].
    in_range : numpy.ndarray of bool
        Whether each candidate is within radio range (sends), [E, C].

    Returns
    -------
    numpy.ndarray
        1.0, 0.0 or NaN per candidate, [E, C].
    """
    with np.errstate(invalid="ignore"):
        ok = np.abs(toa_error_m(toa, d3d_m)) <= TOA_WITHIN_M
    return np.where(in_range, ok.astype(float), np.nan)


def paired_bootstrap_diff(
    a: NDArray, b: NDArray, rng: np.random.Generator, n_boot: int = 2000, level: float = 0.95
) -> tuple[float, float, float]:
    """Difference of means mean(a) - mean(b) of per-epoch values a, b [E, n] (NaN ignored)
    with a bootstrap interval over epochs (the epochs resampled, pairs kept).

    Parameters
    ----------
    a, b : numpy.ndarray
        Paired values, [E, n] each (e.g. :func:`within_share`).
    rng : numpy.random.Generator
        Generator of the resampled epochs.
    n_boot : int
        Bootstrap resamples.
    level : float
        Confidence level of the percentile interval, in (0, 1).

    Returns
    -------
    tuple of float
        (difference, lower end, upper end), in the unit of ``a`` and ``b``.
    """

    def diff(idx):
        return np.nanmean(a[idx]) - np.nanmean(b[idx])

    e = a.shape[0]
    boots = np.array([diff(rng.integers(0, e, e)) for _ in range(n_boot)])
    q = (1 - level) / 2
    return float(diff(np.arange(e))), float(np.quantile(boots, q)), float(np.quantile(boots, 1 - q))


def summarize(
    stacked: dict, truth: dict, receivers: list[str], comps: dict[str, Comparison] | None = None, seed: int = 0
) -> dict:
    """Every comparison's measures: ``{shortcut: {receiver: {...}}}`` with, per decision,
    the changed share, its 95 % interval (clustered by epoch,
    :func:`railradio.stats.clustered_rate`) and the number of decisions; and the
    distributions' comparison: the two-sample KS p-values of the TOA range and AOD errors,
    the TOA-within-5-m shares and their difference with a paired epoch-bootstrap interval.

    ``truth``: ``d3d`` and ``aod`` [E, C] (true 3-D distance and AOD), ``in_range`` [E, C].

    Parameters
    ----------
    stacked : dict
        Path -> receiver -> ``detected``, ``selected``, ``toa`` [full-rate samples], ``aod``
        [rad] (:func:`railradio.nr.study.fidelity_dataset.from_dataset`).
    truth : dict
        ``d3d`` [m], ``aod`` [rad], ``in_range`` (bool), each [E, C].
    receivers : list of str
        Receiver names.
    comps : dict of str to Comparison or None
        Comparisons to measure (``None``: all of :data:`railradio.nr.study.fidelity.COMPARISONS`); those
        whose path is absent from ``stacked`` are skipped.
    seed : int
        Seed of the bootstrap generator.

    Returns
    -------
    dict
        Comparison -> receiver -> ``{decision: {"frac", "lo", "hi", "n"}}`` (shares, 1) and
        ``toa_ks_p``, ``aod_ks_p``, ``within5_off``, ``within5_base``, ``within5_diff``,
        ``within5_diff_lo``, ``within5_diff_hi`` (1).
    """
    from scipy.stats import ks_2samp

    from railradio.stats import clustered_rate

    rng = np.random.default_rng(seed)
    inr = truth["in_range"]
    out = {}
    for name, comp in (COMPARISONS if comps is None else comps).items():
        if comp.off not in stacked:
            continue
        out[name] = {}
        for r in receivers:
            a, b = stacked[comp.off][r], stacked[comp.base][r]
            m = {}
            for k in DECISIONS:
                ev = changed(k, a, b)
                rate = clustered_rate(ev)
                m[k] = {"frac": rate["p"], "lo": rate["lo"], "hi": rate["hi"], "n": rate["n"]}
            ea = toa_error_m(a["toa"], truth["d3d"])[inr]
            eb = toa_error_m(b["toa"], truth["d3d"])[inr]
            ea, eb = ea[np.isfinite(ea)], eb[np.isfinite(eb)]
            m["toa_ks_p"] = float(ks_2samp(ea, eb).pvalue) if ea.size and eb.size else float("nan")
            fa = aod_error_deg(a["aod"], truth["aod"])[inr]
            fb = aod_error_deg(b["aod"], truth["aod"])[inr]
            fa, fb = fa[np.isfinite(fa)], fb[np.isfinite(fb)]
            m["aod_ks_p"] = float(ks_2samp(fa, fb).pvalue) if fa.size and fb.size else float("nan")
            wa = within_share(a["toa"], truth["d3d"], inr)
            wb = within_share(b["toa"], truth["d3d"], inr)
            m["within5_off"], m["within5_base"] = float(np.nanmean(wa)), float(np.nanmean(wb))
            m["within5_diff"], m["within5_diff_lo"], m["within5_diff_hi"] = paired_bootstrap_diff(wa, wb, rng)
            out[name][r] = m
    return out


DIST_TOL = 0.02
"""Largest |difference| of the TOA-within-5-m share (its 95 % interval's ends) under which
two paths' error distributions count as the same [share]."""
KS_ALPHA = 0.05
"""Significance level of the two-sample KS tests."""


def distributions_agree(m: dict) -> bool:
    """KS p-values of the TOA and AOD errors ≥ :data:`KS_ALPHA` and the TOA-within-5-m
    difference's interval inside ±:data:`DIST_TOL`.

    Parameters
    ----------
    m : dict
        One receiver's measures of a comparison (:func:`summarize`): ``toa_ks_p``,
        ``aod_ks_p`` (NaN p-values are ignored), ``within5_diff_lo``, ``within5_diff_hi``.

    Returns
    -------
    bool
        Whether the two paths' error distributions count as the same.
    """
    ks = [p for p in (m["toa_ks_p"], m["aod_ks_p"]) if np.isfinite(p)]
    return all(p >= KS_ALPHA for p in ks) and m["within5_diff_lo"] >= -DIST_TOL and m["within5_diff_hi"] <= DIST_TOL


def bounded(m: dict, noise: dict, stochastic: bool) -> bool:
    """The rule (stated before the paper-scale run): a stochastic comparison is bounded when
    the error distributions agree (:func:`distributions_agree`); a deterministic one when
    every decision's changed share is at most :data:`GOAL_CHANGE_FRAC` — or, for a decision
    that a redraw of the noise alone changes more often than that (``noise``, the same
    receiver's ``noise`` comparison: the decision is not reproducible under the model's own
    randomness), when the error distributions agree.

    Parameters
    ----------
    m : dict
        One receiver's measures of the comparison (:func:`summarize`).
    noise : dict
        The same receiver's measures of the ``noise`` comparison (used only when deterministic).
    stochastic : bool
        Whether the comparison is stochastic (:attr:`railradio.nr.study.fidelity.Comparison.stochastic`).

    Returns
    -------
    bool
        Whether the shortcut is bounded.
    """
    if stochastic:
        return distributions_agree(m)
    for k in DECISIONS:
        if m[k]["frac"] <= GOAL_CHANGE_FRAC:
            continue
        if noise[k]["frac"] > GOAL_CHANGE_FRAC and distributions_agree(m):
            continue
        return False
    return True
