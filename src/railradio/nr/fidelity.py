"""Every shortcut of the nr burst synthesis and receiver, measured where it runs.

The production path (:class:`railradio.nr.receiver.Synthesizer` at F_s/8 and the decimated
coarse-to-fine :class:`railradio.nr.receiver.Correlator`) makes the study fit a 2-core
machine. Its shortcuts are measured here on paper-scale epochs — the paper's ~19 RRHs in
range, their data traffic, the receiver noise, the train's speed — by running, on the same
epoch and the same random draws, the production path and the same path with one shortcut
replaced by the exact computation (:mod:`railradio.nr.reference`: TS 38.211's time-continuous
signal through a per-sample channel):

=============  =================================================================================
shortcut       off (the exact computation)
=============  =================================================================================
``search``     every full-rate lag: the production burst, band-limited-interpolated to F_s,
               through full-rate correlators (no decimated statistics, no prescreen, no ±1
               decimated-lag refinement; the CA-CFAR window and guard the same in time)
``band``       the fast path at the full rate (all 600 subcarriers) instead of its band (the
               central 1024/D_s subcarriers), both through the receiver's front end (ideal
               anti-aliasing filter and sampling at F_s/D, :func:`~railradio.nr.resample.project`)
``form``       the fast path's per-symbol frequency-domain taps (each delayed tap's copy of a
               symbol wrapped cyclically within the symbol's extent: its spill into the next
               symbol omitted) against every tap's own delayed extent, both at the full band
               with the fast path's held geometry and per-symbol taps (exact synthesis)
``spill``      the same as ``form`` at the production's own rate: the production path with each
               delayed tap's spill into the next symbol computed exactly
               (``nr.channel.exact_spill``; only where the production wraps it)
``taps``       Rayleigh taps at every sample instead of held per symbol (against ``form``)
``geometry``   the bulk delay, LOS phase and beam gains following the train through the
               burst (:mod:`railradio.nr.motion`) instead of held at the epoch instant
``far_taps``   every RRH in range fully fading instead of one non-fading tap beyond
               ``nr.channel.full_channel_range_m`` [stochastic: a different fading model]
``noise``      the noise drawn at the decimated rate (production) against the projection of
               full-rate noise [stochastic: exact in distribution, other draws]
``all``        every shortcut off: exact synthesis, full-rate noise, full-rate correlators
=============  =================================================================================

Deterministic comparisons share every draw (data, fading, beams, loads and the noise: the
production and its variants take the projection of the same full-rate noise), so a changed
decision is the shortcut's doing. The decisions, per receiver (the source's and ours): the
detection of each SS block of each candidate, whether each candidate is among the selected
cells, the TOA (changed by more than one full-rate sample, or present in one only) and the
AOD (by more than 0.1°, or present in one only). Stochastic comparisons share the draws as
far as the model allows and are judged on the distributions of the errors (a two-sample
Kolmogorov–Smirnov test and the difference of the TOA-within-5-m share).

Truth is read only to score: every variant's receiver sees the burst, the deployment and the
production's candidate list at that epoch (its cell-search state, read from the main run).
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.antenna import wrap_rad
from railradio.nr.cellsearch import correlation_key, ss_rsrp_db
from railradio.nr.motion import burst_motion
from railradio.nr.numerology import SAMPLE_RATE_HZ
from railradio.nr.receiver import Correlator, Synthesizer
from railradio.nr.reference import full_rate_noise, reference_received
from railradio.nr.resample import project, upsample
from railradio.nr.simulate import KEY_EPOCH, KEY_POOL, Scenario, Synthesis
from railradio.nr.ssb import qpsk_pool
from railradio.rng import make_rng

KEY_FIDELITY_NOISE = 7
"""Sub-key of the full-rate noise draws (below the realization's key; the production's own
draws use KEY_EPOCH)."""

D_FULL = 1


@dataclass(frozen=True)
class Comparison:
    """A shortcut's measurement: the variant with it off against the variant it is
    compared with; ``stochastic`` when the two cannot share every draw."""

    off: str
    base: str
    stochastic: bool = False


COMPARISONS = {
    "search": Comparison("search", "production"),
    "band": Comparison("band", "production"),
    "form": Comparison("form", "band"),
    "spill": Comparison("spill", "production"),
    "taps": Comparison("taps", "form"),
    "geometry": Comparison("geometry", "production"),
    "far_taps": Comparison("far_taps", "production", stochastic=True),
    "noise": Comparison("own_noise", "production", stochastic=True),
    "all": Comparison("exact", "production"),
}
"""Every comparison; ``far_taps`` and ``spill`` only where the production uses that shortcut."""


def comparisons(scn: Scenario) -> dict[str, Comparison]:
    """The comparisons that apply to the scenario's production path."""
    skip = set() if np.isfinite(scn.full_channel_range_m) else {"far_taps"}
    if scn.exact_spill:
        skip.add("spill")
    return {k: c for k, c in COMPARISONS.items() if k not in skip}


DECISIONS = ("detection", "selection", "toa", "aod")
TOA_CHANGE_SAMPLES = 1.0
"""A TOA decision changes when the estimate moves by more than this [full-rate samples]."""
AOD_CHANGE_DEG = 0.1
"""An AOD decision changes when the estimate moves by more than this [deg]."""


@dataclass
class ReceiverDecisions:
    """One receiver's decisions on one burst (arrays over the candidates)."""

    detected: NDArray[np.bool_]  # [cand, block]
    toa_samples: NDArray[np.float64]  # [cand] full-rate samples, NaN: nothing detected
    aod_rad: NDArray[np.float64]  # [cand]
    strength: NDArray[np.float64]  # [cand] what the receiver selects its cells by
    selected: NDArray[np.bool_]  # [cand]


class Receivers:
    """The study's receivers (the source's and the variants, ``Scenario.variants``) and the
    cell search's SS-RSRP correlator at one rate: the front end's (``nr.receiver.decimation``),
    as in production, or a finer one on the front end's samples band-limited-interpolated
    (1: every full-rate lag; the template zero-stuffed, the CA-CFAR window and guard the same
    duration)."""

    def __init__(self, scn: Scenario, selection: dict[str, str], decimation: int, n_use: int = 3):
        base = scn.receiver.decimation
        self.decimation = decimation
        rx = [("seed", scn.receiver, scn.detector)] + list(scn.variants)
        self.names = [name for name, _, _ in rx]
        self.selection = selection
        self.n_use = n_use

        def cor(rc, det, pfa):
            return Correlator(dataclasses.replace(rc, decimation=decimation), det, pfa, template_decimation=base)

        self.cors = [cor(rc, det, scn.pfa) for _, rc, det in rx]
        cs = scn.cell_search
        cs_rc = cs.receiver_config(scn.receiver)
        key = correlation_key(cs_rc, cs.detector, cs.pfa)
        self.cs_shared = next(
            (j for j, (_, rc, det) in enumerate(rx) if correlation_key(rc, det, scn.pfa) == key), None
        )
        self.cs_cor = None if self.cs_shared is not None else cor(cs_rc, cs.detector, cs.pfa)

    def __call__(self, z: NDArray[np.complex64], s_min: int, n1: NDArray, n2: NDArray) -> dict[str, ReceiverDecisions]:
        spectra = {}

        def zf(c):
            if c.n_win not in spectra:
                spectra[c.n_win] = c.window_spectra(z, s_min)
            return spectra[c.n_win]

        res = [c.correlate(z, s_min, n1, n2, zf=zf(c)) for c in self.cors]
        cs_res = (
            res[self.cs_shared]
            if self.cs_shared is not None
            else self.cs_cor.correlate(z, s_min, n1, n2, zf=zf(self.cs_cor))
        )
        rsrp = ss_rsrp_db(cs_res)
        out = {}
        for name, r in zip(self.names, res, strict=True):
            score = np.where(r.detected, (r.eta - r.mu) / np.maximum(r.sigma, 1e-30), -np.inf)
            best = np.where(r.detected.any(axis=1), score.max(axis=1), np.nan)
            strength = {"ss_rsrp": rsrp, "best_score": best, "peak": r.peak_comb}[self.selection[name]]
            ok = np.isfinite(r.aod_rad) & np.isfinite(r.toa_samples)
            s = np.where(ok, np.nan_to_num(strength, nan=-np.inf), -np.inf)
            order = np.argsort(-s)[: self.n_use]  # railradio.nr.tracking.selected, one epoch
            sel = np.zeros(n1.size, dtype=bool)
            sel[order[ok[order]]] = True
            out[name] = ReceiverDecisions(
                r.detected.copy(), r.toa_samples.copy(), r.aod_rad.copy(), np.asarray(strength, float), sel
            )
        return out


class FidelityRun:
    """Runs every variant (:func:`variants`) on epochs of one realization.

    Parameters
    ----------
    scn, seed, key
        The scenario, the config seed and the realization's spawn key (as the main run's).
    selection
        Receiver name -> the strength it selects its cells by (``nr.receiver.selection``).
    """

    def __init__(self, scn: Scenario, seed: int, key: tuple[int, ...], selection: dict[str, str]):
        if scn.receiver.decimation == D_FULL:
            raise ValueError("the production path to measure must be decimated (nr.receiver.decimation > 1)")
        self.scn, self.seed, self.key = scn, seed, key
        self.synthesis = Synthesis(scn, seed, key)
        self.fast = self.synthesis.syn
        pool = qpsk_pool(make_rng(seed, key + (KEY_POOL,)), scn.pool_size)  # the main run's data pool
        # the exact synthesis takes the pool as the fast path uses it ("none": no data, no PBCH)
        self.pool_ref = np.zeros_like(pool) if scn.data_beam == "none" else pool
        self.cfg_full = dataclasses.replace(scn.receiver, decimation=D_FULL)
        self.fast_full = Synthesizer(
            self.cfg_full,
            scn.profile,
            pool,
            scn.n_sinusoids,
            scn.full_channel_range_m,
            scn.data_beam,
            scn.load,
            exact_spill=scn.exact_spill,
        )
        self.far_flat = bool(np.isfinite(scn.full_channel_range_m))
        self.down = self.synthesis.down  # synthesis rate -> the front end's
        self.fast_fading = (
            Synthesizer(
                self.fast.cfg,
                scn.profile,
                pool,
                scn.n_sinusoids,
                np.inf,
                scn.data_beam,
                scn.load,
                exact_spill=scn.exact_spill,
            )
            if self.far_flat
            else None
        )
        self.fast_spill = (
            None
            if scn.exact_spill
            else Synthesizer(
                self.fast.cfg,
                scn.profile,
                pool,
                scn.n_sinusoids,
                scn.full_channel_range_m,
                scn.data_beam,
                scn.load,
                exact_spill=True,
            )
        )
        d_c = scn.search_decimation or scn.receiver.decimation
        self.rx = Receivers(scn, selection, d_c)
        self.rx_exact = Receivers(scn, selection, D_FULL)
        self.comparisons = comparisons(scn)
        self.det_cors = {}
        if any(n == "robust" for n, _, _ in scn.variants):
            for label, (rc, det, kw, attrs) in detector_variants(scn).items():
                c = Correlator(
                    dataclasses.replace(rc, decimation=d_c),
                    det,
                    scn.pfa,
                    template_decimation=scn.receiver.decimation,
                    **kw,
                )
                for k, v in attrs.items():
                    setattr(c, k, v)
                self.det_cors[label] = c

    def epoch(self, epoch: int, cand: NDArray[np.int64], serving: int) -> dict:
        """Every variant's decisions at ``epoch`` on the candidate list ``cand`` (the main
        run's cell search there) with the network's serving RRH ``serving`` (the main run's
        serving-cell state there). Returns ``{"decisions": {variant: {receiver: ...}},
        "truth": {...}, "seconds": {variant: s}}``."""
        scn, d = self.scn, self.scn.receiver.decimation
        d_c = self.rx.decimation
        x, v, a, lb, _ = self.synthesis.advance(epoch)
        t0 = epoch * scn.trajectory.dt_s
        links = lb.links
        link_rrh = lb.rrh if lb.link_rrh is None else lb.link_rrh
        serv = np.asarray(link_rrh) == serving
        flat = np.asarray(lb.link_d2d_m) > scn.full_channel_range_m
        dep = scn.deployment
        n1, n2 = (u[cand] for u in dep.n_id())
        secs = {}

        def clock(name, fn):
            t = time.perf_counter()
            out = fn()
            secs[name] = secs.get(name, 0.0) + time.perf_counter() - t
            return out

        rng_prod = make_rng(self.seed, self.key + (KEY_EPOCH, int(epoch)))
        draws = self.fast.draws(links, rng_prod)
        common = dict(t0_s=t0, d2d_m=lb.link_d2d_m, draws=draws, serving=serv)
        symbols = self.fast.span(float(np.max(links.tau_s)))["symbols"]
        down = self.down

        def fast(syn, **kw):  # a fast-path burst through the front end
            out = syn(links, None, noise=False, **common, **kw)[0]
            return project(out, down)

        # the production burst exactly as the main run makes it (its own noise, drawn at the synthesis rate)
        own, s_min = clock("own_noise", lambda: self.fast(links, rng_prod, **common))
        own = project(own, down)
        z8 = clock("production", lambda: fast(self.fast))
        n_full = full_rate_noise(make_rng(self.seed, self.key + (KEY_FIDELITY_NOISE, int(epoch))), links, z8.size * d)
        n8 = project(n_full, d)  # the front end's noise: what the production's own draw stands for
        motion = burst_motion(lb, scn, x, v, a, t0)
        ref = dict(at_train=self._at_train(links.n, serv))
        z = {"production": z8 + n8, "own_noise": own}  # the front end's samples (F_s/D)
        z["band"] = clock("band", lambda: project(self.fast_full(links, None, noise=False, **common)[0], d)) + n8
        z["geometry"] = clock("geometry", lambda: fast(self.fast, motion=motion)) + n8
        if self.far_flat:
            z["far_taps"] = clock("far_taps", lambda: fast(self.fast_fading)) + n8
        if self.fast_spill is not None:
            z["spill"] = clock("spill", lambda: fast(self.fast_spill)) + n8
        z["form"] = (
            clock(
                "form",
                lambda: project(
                    reference_received(
                        self.cfg_full,
                        links,
                        scn.profile,
                        self.pool_ref,
                        draws,
                        symbols,
                        t0,
                        symbol_taps=True,
                        flat=flat,
                        **ref,
                    ),
                    d,
                ),
            )
            + n8
        )
        z["taps"] = (
            clock(
                "taps",
                lambda: project(
                    reference_received(
                        self.cfg_full, links, scn.profile, self.pool_ref, draws, symbols, t0, flat=flat, **ref
                    ),
                    d,
                ),
            )
            + n8
        )
        z["exact"] = (
            clock(
                "exact",
                lambda: project(
                    reference_received(
                        self.cfg_full, links, scn.profile, self.pool_ref, draws, symbols, t0, motion=motion, **ref
                    ),
                    d,
                ),
            )
            + n8
        )
        dec = {}
        for name, zz in z.items():
            if name == "exact":
                continue
            dec[name] = clock(name, lambda zz=zz: self.rx(upsample(zz, d // d_c), s_min, n1, n2))
        z_c = upsample(z["production"], d // d_c)
        detector = {}
        for label, c in self.det_cors.items():  # our detector's constants, one at a time
            r = c.correlate(z_c, s_min, n1, n2)
            detector[label] = {"toa": r.toa_samples, "aod": r.aod_rad, "n_detected": r.detected.sum(axis=1)}
        # interference only: the anchor cell (the list's first) silent, its PCI still searched
        keep = np.asarray(link_rrh) != cand[0]
        sub = _subset_links(links, keep)
        z_int = self.fast(
            sub,
            None,
            noise=False,
            t0_s=t0,
            d2d_m=np.asarray(lb.link_d2d_m)[keep],
            draws=[dr for dr, k in zip(draws, keep, strict=True) if k],
            serving=serv[keep],
        )[0]
        z_int = project(z_int, down)
        z_int = z_int[: z8.size] if z_int.size >= z8.size else np.pad(z_int, (0, z8.size - z_int.size))
        fa_int = {
            name: int(r.detected.sum())
            for name, r in self.rx(upsample(z_int + n8, d // d_c), s_min, n1[:1], n2[:1]).items()
        }
        dec["search"] = clock("search", lambda: self.rx_exact(upsample(z["production"], d), s_min, n1, n2))
        dec["exact"] = clock("exact", lambda: self.rx_exact(upsample(z["exact"], d), s_min, n1, n2))
        # truth, for scoring only
        inr = np.isin(cand, lb.rrh)
        pos = np.searchsorted(lb.rrh, cand[inr])
        d3d = dep.distance_3d_m(np.full(cand.size, x), cand)
        aod = dep.aod_rad(np.full(cand.size, x), cand)
        d3d[inr], aod[inr] = lb.d3d_m[pos], lb.aod_rad[pos]
        p_all = 10 ** (lb.rx_power_dbm / 10)
        truth = dict(
            x=x,
            v=v,
            a=a,
            d3d=d3d,
            aod=aod,
            in_range=inr,
            n_links=links.n,
            sir_db=10 * np.log10(p_all.max() / (p_all.sum() - p_all.max())),
        )
        return {
            "decisions": dec,
            "truth": truth,
            "seconds": secs,
            "detector": detector,
            "interference_false_alarms": fa_int,
            "cand": np.asarray(cand),
            "epoch": int(epoch),
        }

    def _at_train(self, n: int, serv: NDArray[np.bool_]) -> NDArray[np.bool_]:
        """The links whose data go toward the train under the scenario's traffic policy."""
        dbm = self.scn.data_beam
        if dbm == "train":
            return np.ones(n, dtype=bool)
        return serv if dbm == "serving" else np.zeros(n, dtype=bool)


def _subset_links(links, keep: NDArray[np.bool_]):
    """The :class:`railradio.nr.receiver.Links` of the links ``keep`` marks."""
    arrays = {f.name: getattr(links, f.name) for f in dataclasses.fields(links)}
    out = {k: (v[keep] if isinstance(v, np.ndarray) and v.shape[:1] == keep.shape else v) for k, v in arrays.items()}
    return type(links)(**out)


def toa_error_m(toa_samples: NDArray, d3d_m: NDArray) -> NDArray[np.float64]:
    """TOA range error [m] (NaN where nothing was detected)."""
    return toa_samples / SAMPLE_RATE_HZ * SPEED_OF_LIGHT_M_S - d3d_m


def aod_error_deg(aod_rad: NDArray, aod_true_rad: NDArray) -> NDArray[np.float64]:
    return np.degrees(wrap_rad(aod_rad - aod_true_rad))


def changed(kind: str, a: dict[str, NDArray], b: dict[str, NDArray]) -> NDArray[np.float64]:
    """Per-decision change indicators of decision ``kind`` between two runs' arrays
    (``detected`` [E, C, B], ``selected``/``toa``/``aod`` [E, C]): 1 changed, 0 not, NaN
    where neither run made that decision (no TOA/AOD in either). Returns [E, n]."""
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
    """The per-epoch results of :meth:`FidelityRun.epoch` as arrays:
    ``{variant: {receiver: {"detected" [E, C, B], "selected", "toa", "aod" [E, C]}}}``."""
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
    TOA counts as not), NaN for candidates out of range (they send nothing)."""
    with np.errstate(invalid="ignore"):
        ok = np.abs(toa_error_m(toa, d3d_m)) <= TOA_WITHIN_M
    return np.where(in_range, ok.astype(float), np.nan)


def paired_bootstrap_diff(
    a: NDArray, b: NDArray, rng: np.random.Generator, n_boot: int = 2000, level: float = 0.95
) -> tuple[float, float, float]:
    """Difference of means mean(a) - mean(b) of per-epoch values a, b [E, n] (NaN ignored)
    with a bootstrap interval over epochs (the epochs resampled, pairs kept)."""

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
    :func:`railradio.handover.stats.clustered_rate`) and the number of decisions; and the
    distributions' comparison: the two-sample KS p-values of the TOA range and AOD errors,
    the TOA-within-5-m shares and their difference with a paired epoch-bootstrap interval.

    ``truth``: ``d3d`` and ``aod`` [E, C] (true 3-D distance and AOD), ``in_range`` [E, C]."""
    from scipy.stats import ks_2samp

    from railradio.handover.stats import clustered_rate

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


# ---- the sample of epochs -------------------------------------------------------------------


def sample_epochs(n_run: int, n: int, change_epochs: NDArray, speed_m_s: NDArray) -> NDArray[np.int64]:
    """``n`` epochs of a run of ``n_run``: the acceleration changes (``change_epochs``, those
    inside the run) and the epoch of the highest speed, the rest spread evenly from the first
    epoch to the last (a rule fixed before any result)."""
    if not 1 <= n <= n_run:
        raise ValueError(f"n must be in 1..{n_run}, got {n!r}")
    forced = {int(e) for e in np.asarray(change_epochs) if 0 <= e < n_run}
    forced.add(int(np.argmax(np.asarray(speed_m_s)[:n_run])))
    forced = sorted(forced)[:n]
    rest = np.round(np.linspace(0, n_run - 1, n - len(forced))).astype(np.int64) if n > len(forced) else []
    out = np.unique(np.concatenate([np.asarray(forced, np.int64), rest]))
    k = 0  # fill places lost to coincidences with the nearest free epochs
    while out.size < n:
        cand = int(np.round((k + 0.5) * n_run / n)) % n_run
        out = np.unique(np.append(out, cand))
        k += 1
    return out


# ---- the detector: its constants and false alarms (measured on the same epochs) --------------

DETECTOR_SETTINGS = {
    "ca_window": (256, 1024),  # full-rate lags on each side (the default CA_WINDOW_FULL: 512)
    "ca_guard": (16, 64),  # full-rate guard lags (default CA_GUARD_FULL: 32)
    "ca_prescreen": (0.6, 0.9),  # share of the threshold (default CA_PRESCREEN: 0.8)
    "toa_blocks": (
        1,
        2,
        4,
        6,
        0,
    ),  # the most significant detected blocks combined (0: all; default nr.receiver_variants)
}
"""One-at-a-time settings of our receiver's detector constants around the defaults."""


def detector_variants(scn: Scenario, name: str = "robust") -> dict[str, tuple]:
    """{label: (ReceiverConfig, detector, Correlator kwargs, attribute overrides)} for the
    settings of :data:`DETECTOR_SETTINGS` applied to the receiver ``name`` of ``scn.variants``."""
    from railradio.nr.receiver import CA_GUARD_FULL, CA_WINDOW_FULL

    rc, det = next((rc, det) for n, rc, det in scn.variants if n == name)
    d_c = scn.search_decimation or scn.receiver.decimation
    out = {}
    for key, values in DETECTOR_SETTINGS.items():
        for v in values:
            kw, attrs, cfg = {}, {}, rc
            if key == "ca_window":
                kw["ca_window"] = v // d_c
            elif key == "ca_guard":
                kw["ca_guard"] = v // d_c
            elif key == "ca_prescreen":
                attrs["ca_prescreen"] = v
            else:
                cfg = dataclasses.replace(rc, toa_blocks=None if v == 0 else v)
            out[f"{key}_{v}"] = (cfg, det, kw, attrs)
    assert CA_WINDOW_FULL not in DETECTOR_SETTINGS["ca_window"] and CA_GUARD_FULL not in DETECTOR_SETTINGS["ca_guard"]
    return out


def noise_false_alarms(
    scn: Scenario, n_bursts: int, rng: np.random.Generator, n_cells: int = 6
) -> dict[str, tuple[int, int]]:
    """False alarms of every receiver on noise-only bursts: ``{receiver: (detections,
    block tests)}``. Each burst is complex white noise at the front end's rate with the
    production burst's length, tested for ``n_cells`` cells drawn from the deployment."""
    rx = Receivers(
        scn,
        {n: "peak" for n, _, _ in [("seed", None, None)] + list(scn.variants)},
        scn.search_decimation or scn.receiver.decimation,
    )
    d = scn.receiver.decimation
    fast = Synthesizer(scn.receiver, scn.profile, np.zeros((1, 1024), np.complex64))
    sp = fast.span(0.0)
    n1_all, n2_all = scn.deployment.n_id()
    counts = {name: [0, 0] for name in rx.names}
    for _ in range(n_bursts):
        z = ((rng.standard_normal(sp["total"]) + 1j * rng.standard_normal(sp["total"])) / np.sqrt(2)).astype(
            np.complex64
        )
        cells = rng.choice(n1_all.size, size=n_cells, replace=False)
        out = rx(upsample(z, d // rx.decimation), sp["s_min"], n1_all[cells], n2_all[cells])
        for name, dec in out.items():
            counts[name][0] += int(dec.detected.sum())
            counts[name][1] += int(dec.detected.size)
    return {k: (v[0], v[1]) for k, v in counts.items()}


# ---- datasets -------------------------------------------------------------------------------


def to_dataset(results: list[dict], receivers: list[str]):
    """The per-epoch results of :meth:`FidelityRun.epoch` as an :class:`xarray.Dataset`."""
    import xarray as xr

    variants = list(results[0]["decisions"])
    settings = list(results[0]["detector"])
    st = stack(results, receivers)
    ep = np.array([r["epoch"] for r in results])
    n_b = st[variants[0]][receivers[0]]["detected"].shape[-1]
    n_c = results[0]["cand"].size

    def per(key):
        return np.stack([np.stack([st[v][r][key] for r in receivers]) for v in variants])

    t = {k: np.stack([r["truth"][k] for r in results]) for k in ("d3d", "aod", "in_range")}
    s = {k: np.array([r["truth"][k] for r in results], float) for k in ("x", "v", "a", "sir_db", "n_links")}
    vr, dims = ("variant", "receiver", "epoch", "cand"), ("epoch", "cand")
    ds = xr.Dataset(
        {
            "detected": (
                vr + ("block",),
                per("detected").astype(np.int8),
                {"units": "1", "long_name": "SS block detected"},
            ),
            "selected": (
                vr,
                per("selected").astype(np.int8),
                {"units": "1", "long_name": "candidate among the receiver's selected cells"},
            ),
            "toa": (
                vr,
                per("toa"),
                {"units": "1", "long_name": "TOA estimate in full-rate samples (NaN: nothing detected)"},
            ),
            "aod": (vr, per("aod"), {"units": "rad", "long_name": "AOD estimate (NaN: nothing detected)"}),
            "rrh": (
                dims,
                np.stack([r["cand"] for r in results]),
                {"units": "1", "long_name": "candidate RRH (the main run's neighbour list)"},
            ),
            "d3d": (dims, t["d3d"], {"units": "m", "long_name": "true 3-D distance (scoring only)"}),
            "aod_true": (dims, t["aod"], {"units": "rad", "long_name": "true AOD (scoring only)"}),
            "in_range": (
                dims,
                t["in_range"].astype(np.int8),
                {"units": "1", "long_name": "the candidate transmits (within nr.radio.range_m)"},
            ),
            "x_true": (("epoch",), s["x"], {"units": "m", "long_name": "true train position"}),
            "v_true": (("epoch",), s["v"], {"units": "m s-1", "long_name": "true speed"}),
            "a_true": (("epoch",), s["a"], {"units": "m s-2", "long_name": "true acceleration"}),
            "sir_best": (
                ("epoch",),
                s["sir_db"],
                {"units": "dB", "long_name": "strongest RRH's power over the sum of the others"},
            ),
            "n_links": (("epoch",), s["n_links"], {"units": "1", "long_name": "RRHs in range (synthesized)"}),
            "seconds": (
                ("variant", "epoch"),
                np.array([[r["seconds"].get(v, np.nan) for r in results] for v in variants]),
                {"units": "s", "long_name": "wall time of the variant's synthesis and correlation (one core)"},
            ),
            "det_toa": (
                ("setting",) + dims,
                np.stack([np.stack([r["detector"][k]["toa"] for r in results]) for k in settings]),
                {
                    "units": "1",
                    "long_name": "our receiver's TOA [full-rate samples] with one detector constant changed",
                },
            ),
            "det_n_detected": (
                ("setting",) + dims,
                np.stack([np.stack([r["detector"][k]["n_detected"] for r in results]) for k in settings]),
                {"units": "1", "long_name": "our receiver's detected blocks with one detector constant changed"},
            ),
            "fa_interference": (
                ("receiver", "epoch"),
                np.array([[r["interference_false_alarms"][rx] for r in results] for rx in receivers]),
                {
                    "units": "1",
                    "long_name": "blocks detected for the anchor cell's PCI with the anchor silent (of n_blocks)",
                },
            ),
        },
        coords={
            "variant": ("variant", variants, {"units": "1", "long_name": "synthesis and receiver path"}),
            "receiver": ("receiver", receivers, {"units": "1", "long_name": "receiver"}),
            "epoch": ("epoch", ep, {"units": "1", "long_name": "epoch of the main run's realization"}),
            "cand": ("cand", np.arange(n_c), {"units": "1", "long_name": "place in the neighbour list"}),
            "block": ("block", np.arange(n_b), {"units": "1", "long_name": "SS block"}),
            "setting": ("setting", settings, {"units": "1", "long_name": "our detector with one constant changed"}),
        },
    )
    return ds


def from_dataset(ds) -> tuple[dict, dict]:
    """``(stacked, truth)`` for :func:`summarize` from a (concatenated) fidelity dataset."""
    stacked = {}
    for v in ds["variant"].values:
        stacked[str(v)] = {}
        for r in ds["receiver"].values:
            sel = ds.sel(variant=v, receiver=r)
            stacked[str(v)][str(r)] = {
                "detected": sel["detected"].values.astype(bool),
                "selected": sel["selected"].values.astype(bool),
                "toa": sel["toa"].values,
                "aod": sel["aod"].values,
            }
    truth = {"d3d": ds["d3d"].values, "aod": ds["aod_true"].values, "in_range": ds["in_range"].values.astype(bool)}
    return stacked, truth


# ---- verdicts and key numbers -----------------------------------------------------------------

DIST_TOL = 0.02
"""Largest |difference| of the TOA-within-5-m share (its 95 % interval's ends) under which
two paths' error distributions count as the same [share]."""
KS_ALPHA = 0.05
"""Significance level of the two-sample KS tests."""


def distributions_agree(m: dict) -> bool:
    """KS p-values of the TOA and AOD errors ≥ :data:`KS_ALPHA` and the TOA-within-5-m
    difference's interval inside ±:data:`DIST_TOL`."""
    ks = [p for p in (m["toa_ks_p"], m["aod_ks_p"]) if np.isfinite(p)]
    return all(p >= KS_ALPHA for p in ks) and m["within5_diff_lo"] >= -DIST_TOL and m["within5_diff_hi"] <= DIST_TOL


def bounded(m: dict, noise: dict, stochastic: bool) -> bool:
    """The rule (stated before the paper-scale run): a stochastic comparison is bounded when
    the error distributions agree (:func:`distributions_agree`); a deterministic one when
    every decision's changed share is at most :data:`GOAL_CHANGE_FRAC` — or, for a decision
    that a redraw of the noise alone changes more often than that (``noise``, the same
    receiver's ``noise`` comparison: the decision is not reproducible under the model's own
    randomness), when the error distributions agree."""
    if stochastic:
        return distributions_agree(m)
    for k in DECISIONS:
        if m[k]["frac"] <= GOAL_CHANGE_FRAC:
            continue
        if noise[k]["frac"] > GOAL_CHANGE_FRAC and distributions_agree(m):
            continue
        return False
    return True


DECISION_LABEL = {
    "detection": "SS-block detection",
    "selection": "selected cells",
    "toa": "TOA (> 1 full-rate sample)",
    "aod": "AOD (> 0.1 deg)",
}
COMPARISON_LABEL = {
    "search": "the decimated coarse-to-fine search against every full-rate lag",
    "band": "the band-limited synthesis against the full band through the front end",
    "form": "each tap's symbols wrapped within their extent against the taps' spill kept",
    "spill": "each tap's symbols wrapped within their extent against the taps' spill kept, at the production's rate",
    "taps": "Rayleigh taps held per symbol against per sample",
    "geometry": "the geometry held over the burst against the train's motion",
    "far_taps": "far interferers as one non-fading tap against fully fading",
    "noise": "a redraw of the noise (decimated against full-rate, projected)",
    "all": "the production path against the exact computation",
}


def key_numbers(summary: dict, comps: dict[str, Comparison], n_epochs: int, seconds: dict[str, float]) -> dict:
    """Key numbers ``nr.fidelity.*`` from :func:`summarize`'s output."""
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
    all_ok = True
    for c, per in summary.items():
        comp = comps[c]
        c_ok = True
        for r, m in per.items():
            where = f"{COMPARISON_LABEL[c]}, receiver {r}"
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
                f"1: bounded by the rule of railradio.nr.fidelity.bounded, 0: not ({where})",
                float(ok),
            )
            c_ok &= ok
        put(
            f"nr.fidelity.{c}.bounded", "1", f"1: {COMPARISON_LABEL[c]} bounded for every receiver, 0: not", float(c_ok)
        )
        all_ok &= c_ok
    put("nr.fidelity.all_bounded", "1", "1: every comparison bounded for every receiver, 0: not", float(all_ok))
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
    time (the TOA-within-5-m share and the detected blocks per candidate in range)."""
    from railradio.handover.stats import clustered_rate, wilson_interval
    from railradio.keynumbers import KeySpec

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
    prod = ds.sel(variant="production", receiver="robust")
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


NOISE_ONLY_ID = 2000
"""Realization ID of the noise-only bursts' generator (the main run's are 0, 1, …; the
calibration run's 1000)."""


def check_production(res: dict, main_row, receivers: list[str]) -> None:
    """Raise when the production path re-run here (``own_noise``: its own draws) differs from
    the main run's estimates at that epoch (``main_row``: one epoch of its shards) — the
    comparisons would then not be about the production path."""
    from railradio.nr.numerology import SAMPLE_RATE_HZ as FS

    for j, r in enumerate(receivers):
        d = res["decisions"]["own_noise"][r]
        toa = main_row["toa_hat"].values[j] * FS
        aod = main_row["aod_hat"].values[j]
        if not (
            np.allclose(d.toa_samples, toa, rtol=0, atol=1e-6, equal_nan=True)
            and np.array_equal(d.aod_rad, aod, equal_nan=True)
        ):
            raise ValueError(
                f"epoch {res['epoch']}, receiver {r}: the production path differs from the main run's "
                f"estimates (TOA {d.toa_samples} vs {toa})"
            )
