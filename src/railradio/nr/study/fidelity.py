"""Every shortcut of the nr burst synthesis and receiver, measured where it runs.

The production path (:class:`railradio.nr.synthesis.synthesizer.Synthesizer` at F_s/8 and the decimated
coarse-to-fine :class:`railradio.nr.receiver.correlator.Correlator`) makes the study fit a 2-core
machine. Its shortcuts are measured here on paper-scale epochs — the paper's ~19 RRHs in
range, their data traffic, the receiver noise, the train's speed — by running, on the same
epoch and the same random draws, the production path and the same path with one shortcut
replaced by the exact computation (:mod:`railradio.nr.synthesis.reference`: TS 38.211's time-continuous
signal through a per-sample channel):

=============  =================================================================================
shortcut       off (the exact computation)
=============  =================================================================================
``search``     every full-rate lag: the production burst, band-limited-interpolated to F_s,
               through full-rate correlators (no decimated statistics, no prescreen, no ±1
               decimated-lag refinement; the CA-CFAR window and guard the same in time)
``band``       the fast path at the full rate (all 600 subcarriers) instead of its band (the
               central 1024/D_s subcarriers) plus, with ``nr.channel.band_edges``, the full
               band's symbol edges inside the front end's band
               (:class:`railradio.nr.synthesis.band_edges.BandEdges`: then only their interpolation is
               measured), both through the receiver's front end (ideal anti-aliasing filter
               and sampling at F_s/D, :func:`~railradio.nr.receiver.frontend.project`)
``form``       the fast path's per-symbol frequency-domain taps (without ``exact_spill``, each
               delayed tap's copy of a symbol wrapped cyclically within the symbol's extent:
               its spill into the next symbol omitted) against every tap's own delayed extent,
               both at the full band with the fast path's held geometry and per-symbol taps
               (exact synthesis); with ``exact_spill`` it checks the exact spill
``spill``      the same as ``form`` at the production's own rate: the production path with each
               delayed tap's spill into the next symbol wrapped and computed exactly
               (``nr.channel.exact_spill``); where the production computes it exactly, the
               wrapped path is the shortcut not taken, measured all the same (``taken`` false)
``taps``       Rayleigh taps at every sample instead of held per symbol (against ``form``)
``geometry``   the bulk delay, LOS phase and beam gains following the train through the
               burst (:mod:`railradio.nr.channel.motion`) instead of held at the epoch instant
``far_taps``   every RRH in range fully fading instead of one non-fading tap beyond
               ``nr.channel.full_channel_range_m`` [stochastic: a different fading model]
``noise``      the noise drawn at the decimated rate (production) against the projection of
               full-rate noise [stochastic: exact in distribution, other draws]
``all``        every shortcut off: exact synthesis, full-rate noise, full-rate correlators
=============  =================================================================================

Deterministic comparisons share every draw (data, fading, beams, loads and the noise: the
production and its paths take the projection of the same full-rate noise), so a changed
decision is the shortcut's doing. The decisions, per receiver (the source's and ours): the
detection of each SS block of each candidate, whether each candidate is among the selected
cells, the TOA (changed by more than one full-rate sample, or present in one only) and the
AOD (by more than 0.1°, or present in one only). Stochastic comparisons share the draws as
far as the model allows and are judged on the distributions of the errors (a two-sample
Kolmogorov–Smirnov test and the difference of the TOA-within-5-m share).

Truth is read only to score: every path's receiver sees the burst, the deployment and the
production's candidate list at that epoch (its cell-search state, read from the main run).

This module holds the comparisons and the run; the measures and the rule a shortcut is
judged by are in :mod:`railradio.nr.study.fidelity_stats`, the key numbers in
:mod:`railradio.nr.study.fidelity_keys`, the datasets in :mod:`railradio.nr.study.fidelity_dataset`, the
receivers' decisions in :mod:`railradio.nr.study.fidelity_receivers` and our detector's constants
and false alarms in :mod:`railradio.nr.study.fidelity_detector`.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from railradio.nr.channel.motion import burst_motion
from railradio.nr.engine.simulate import KEY_EPOCH, KEY_POOL, Scenario, Synthesis
from railradio.nr.receiver.correlator import Correlator
from railradio.nr.receiver.frontend import project, upsample
from railradio.nr.study.fidelity_detector import detector_setting_receivers
from railradio.nr.study.fidelity_receivers import Receivers
from railradio.nr.synthesis.band_edges import BandEdges
from railradio.nr.synthesis.reference import full_rate_noise, reference_received
from railradio.nr.synthesis.synthesizer import Synthesizer
from railradio.nr.waveform.ssb import qpsk_pool
from railradio.rng import make_rng

KEY_FIDELITY_NOISE = 7
"""Sub-key of the full-rate noise draws (below the realization's key; the production's own
draws use KEY_EPOCH)."""

D_FULL = 1


@dataclass(frozen=True)
class Comparison:
    """A shortcut's measurement: the path with it off against the path it is
    compared with; ``stochastic`` when the two cannot share every draw; ``taken`` false when
    the production path does not use the shortcut (it is measured to show what it would
    change, and left out of :func:`railradio.nr.study.fidelity_keys.key_numbers`' overall verdict)."""

    off: str
    base: str
    stochastic: bool = False
    taken: bool = True


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
"""Every comparison; ``far_taps`` only where the production uses that shortcut."""


def comparisons(scn: Scenario) -> dict[str, Comparison]:
    """The comparisons that apply to the scenario's production path.

    Parameters
    ----------
    scn : Scenario
        The scenario whose production path is measured.

    Returns
    -------
    dict of str to Comparison
        The entries of :data:`COMPARISONS` without ``far_taps`` (no far-tap shortcut:
        ``full_channel_range_m`` infinite); ``spill`` not ``taken`` when ``exact_spill`` is set
        (the production computes the spill exactly; the wrapped path is the alternative).
    """
    skip = set() if np.isfinite(scn.full_channel_range_m) else {"far_taps"}
    out = {k: c for k, c in COMPARISONS.items() if k not in skip}
    if scn.exact_spill:
        out["spill"] = dataclasses.replace(out["spill"], taken=False)
    return out


DECISIONS = ("detection", "selection", "toa", "aod")
TOA_CHANGE_SAMPLES = 1.0
"""A TOA decision changes when the estimate moves by more than this [full-rate samples]."""
AOD_CHANGE_DEG = 0.1
"""An AOD decision changes when the estimate moves by more than this [deg]."""


@dataclass(frozen=True)
class _EpochInputs:
    """What every path shares at one epoch: the truth (to synthesize and to score; no
    receiver reads it), the candidates' cell IDs, the production's draws, and the paths'
    wall times [s] (``secs``, by :meth:`clock`)."""

    epoch: int
    t0_s: float
    x_m: float
    v_m_s: float
    a_m_s2: float
    lb: object  # railradio.nr.channel.link.LinkBudget
    cand: NDArray[np.int64]
    link_rrh: NDArray[np.int64]
    serv: NDArray[np.bool_]  # [link] the network's serving RRH
    flat: NDArray[np.bool_]  # [link] beyond nr.channel.full_channel_range_m
    n1: NDArray[np.int64]  # [cand]
    n2: NDArray[np.int64]  # [cand]
    rng_prod: np.random.Generator
    draws: list
    common: dict
    symbols: object
    secs: dict[str, float] = field(default_factory=dict)

    @property
    def links(self):
        return self.lb.links

    def clock(self, name: str, fn):
        """``fn()``, its wall time added to ``secs[name]``."""
        t = time.perf_counter()
        out = fn()
        self.secs[name] = self.secs.get(name, 0.0) + time.perf_counter() - t
        return out


class _Bursts(NamedTuple):
    """Every path's burst at the front end (F_s/D) at one epoch."""

    z: dict[str, NDArray[np.complex64]]
    s_min: int  # the production burst's start
    noise: NDArray[np.complex64]  # the front end's noise, shared by every path but own_noise
    n_samples: int  # the production burst's length at the front end


class FidelityRun:
    """Runs every path (those of :data:`COMPARISONS`) on epochs of one realization.

    Parameters
    ----------
    scn, seed, key : Scenario, int, tuple of int
        The scenario, the config seed and the realization's spawn key (as the main run's).
    selection : dict of str to str
        Receiver name -> the strength it selects its cells by (``nr.receiver.selection``).

    Raises
    ------
    ValueError
        When the production path is not decimated (``scn.receiver.decimation`` == 1), or a
        synthesis decimation does not divide the front end's (:class:`Synthesis`).
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
        self.fast_spill = Synthesizer(  # the production's other spill setting
            self.fast.cfg,
            scn.profile,
            pool,
            scn.n_sinusoids,
            scn.full_channel_range_m,
            scn.data_beam,
            scn.load,
            exact_spill=not scn.exact_spill,
        )
        # every path at the synthesis rate adds its own band's edges, as the production does
        self.edges = {
            id(syn): BandEdges(syn, pool, scn.receiver.decimation) if self.synthesis.edges is not None else None
            for syn in (self.fast_fading, self.fast_spill)
            if syn is not None
        }
        self.edges[id(self.fast)] = self.synthesis.edges
        d_c = scn.search_decimation or scn.receiver.decimation
        self.rx = Receivers(scn, selection, d_c)
        self.rx_exact = Receivers(scn, selection, D_FULL)
        self.comparisons = comparisons(scn)
        self.det_cors = {}
        if any(n == "robust" for n, _, _ in scn.extra_receivers):
            for label, (rc, det, kw, attrs) in detector_setting_receivers(scn).items():
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
        """Every path's decisions at ``epoch`` on the candidate list ``cand`` (the main
        run's cell search there) with the network's serving RRH ``serving`` (the main run's
        serving-cell state there). Returns ``{"decisions": {path: {receiver: ...}},
        "truth": {...}, "seconds": {path: s}}``.

        Parameters
        ----------
        epoch : int
            Epoch index of the main run's realization.
        cand : numpy.ndarray of int64
            RRH indices of the main run's candidate list at ``epoch``.
        serving : int
            The network's serving RRH there.

        Returns
        -------
        dict
            ``decisions`` (path -> receiver -> decisions), ``truth``, ``seconds`` (path ->
            computing time, s), ``detector`` (setting -> ``toa`` [full-rate samples], ``aod`` [rad],
            ``n_detected`` of our detector with one constant changed; empty without a ``robust``
            receiver), ``interference_false_alarms`` (on interference-only bursts), ``cand``, ``epoch``.
        """
        ep = self._inputs(epoch, cand, serving)
        bursts = self._bursts(ep)
        dec, detector, fa_int = self._decisions(ep, bursts)
        return {
            "decisions": dec,
            "truth": self._truth(ep),
            "seconds": ep.secs,
            "detector": detector,
            "interference_false_alarms": fa_int,
            "cand": np.asarray(cand),
            "epoch": int(epoch),
        }

    def _inputs(self, epoch: int, cand: NDArray[np.int64], serving: int) -> _EpochInputs:
        """The truth at ``epoch``, the candidates' cell IDs and the production's draws (the
        main run's, keyed by (realization, epoch))."""
        scn = self.scn
        x, v, a, lb, _ = self.synthesis.advance(epoch)
        t0 = epoch * scn.trajectory.dt_s
        links = lb.links
        link_rrh = lb.rrh if lb.link_rrh is None else lb.link_rrh
        serv = np.asarray(link_rrh) == serving
        flat = np.asarray(lb.link_d2d_m) > scn.full_channel_range_m
        n1, n2 = (u[cand] for u in scn.deployment.n_id())
        rng_prod = make_rng(self.seed, self.key + (KEY_EPOCH, int(epoch)))
        draws = self.fast.draws(links, rng_prod)
        common = dict(t0_s=t0, d2d_m=lb.link_d2d_m, draws=draws, serving=serv)
        symbols = self.fast.span(float(np.max(links.tau_s)))["symbols"]
        return _EpochInputs(
            epoch, t0, x, v, a, lb, cand, link_rrh, serv, flat, n1, n2, rng_prod, draws, common, symbols
        )

    def _bursts(self, ep: _EpochInputs) -> _Bursts:
        """Every path's burst through the front end: the production's with its own noise
        (``own_noise``), every other with the projection of the same full-rate noise."""
        scn, d = self.scn, self.scn.receiver.decimation
        links, common, down = ep.links, ep.common, self.down

        def fast(syn, **kw):  # a fast-path burst through the front end, with its band's edges
            out = project(syn(links, None, noise=False, **common, **kw)[0], down)
            return out + self._edges(syn, ep, links, ep.draws, ep.lb.link_d2d_m, ep.serv, kw.get("motion"))

        # the production burst exactly as the main run makes it (its own noise, drawn at the synthesis rate)
        own, s_min = ep.clock("own_noise", lambda: self.fast(links, ep.rng_prod, **common))
        own = ep.clock(
            "own_noise",
            lambda: project(own, down) + self._edges(self.fast, ep, links, ep.draws, ep.lb.link_d2d_m, ep.serv),
        )
        z8 = ep.clock("production", lambda: fast(self.fast))
        n_full = full_rate_noise(
            make_rng(self.seed, self.key + (KEY_FIDELITY_NOISE, int(ep.epoch))), links, z8.size * d
        )
        n8 = project(n_full, d)  # the front end's noise: what the production's own draw stands for
        motion = burst_motion(ep.lb, scn, ep.x_m, ep.v_m_s, ep.a_m_s2, ep.t0_s)
        ref = dict(at_train=self._at_train(links.n, ep.serv))
        z = {"production": z8 + n8, "own_noise": own}  # the front end's samples (F_s/D)
        z["band"] = ep.clock("band", lambda: project(self.fast_full(links, None, noise=False, **common)[0], d)) + n8
        z["geometry"] = ep.clock("geometry", lambda: fast(self.fast, motion=motion)) + n8
        if self.far_flat:
            z["far_taps"] = ep.clock("far_taps", lambda: fast(self.fast_fading)) + n8
        z["spill"] = ep.clock("spill", lambda: fast(self.fast_spill)) + n8
        z["form"] = self._exact(ep, "form", symbol_taps=True, flat=ep.flat, **ref) + n8
        z["taps"] = self._exact(ep, "taps", flat=ep.flat, **ref) + n8
        z["exact"] = self._exact(ep, "exact", motion=motion, **ref) + n8
        return _Bursts(z, s_min, n8, z8.size)

    def _edges(self, syn: Synthesizer, ep: _EpochInputs, links, draws, d2d_m, serv, motion=None):
        """The band's edges (:class:`railradio.nr.synthesis.band_edges.BandEdges`) of the burst ``syn``
        has just made from ``draws`` (its kept tap gains), 0 without ``nr.channel.band_edges``."""
        edges = self.edges[id(syn)]
        if edges is None:
            return 0.0
        return edges(links, draws, ep.t0_s, d2d_m, serv, motion=motion, gains=syn.kept_gains)

    def _exact(self, ep: _EpochInputs, name: str, **kw) -> NDArray[np.complex64]:
        """The exact synthesis (:func:`railradio.nr.synthesis.reference.reference_received` with ``kw``,
        its wall time as ``name``) through the front end, without noise."""
        return ep.clock(
            name,
            lambda: project(
                reference_received(
                    self.cfg_full, ep.links, self.scn.profile, self.pool_ref, ep.draws, ep.symbols, ep.t0_s, **kw
                ),
                self.scn.receiver.decimation,
            ),
        )

    def _decisions(self, ep: _EpochInputs, b: _Bursts) -> tuple[dict, dict, dict[str, int]]:
        """Every path's decisions per receiver, our detector's constants one at a time on the
        production burst, and the interference-only false alarms."""
        d, d_c = self.scn.receiver.decimation, self.rx.decimation
        s_min, n1, n2 = b.s_min, ep.n1, ep.n2
        dec = {}
        for name, zz in b.z.items():
            if name == "exact":
                continue
            dec[name] = ep.clock(name, lambda zz=zz: self.rx(upsample(zz, d // d_c), s_min, n1, n2))
        z_c = upsample(b.z["production"], d // d_c)
        detector = {}
        for label, c in self.det_cors.items():  # our detector's constants, one at a time
            r = c.correlate(z_c, s_min, n1, n2)
            detector[label] = {"toa": r.toa_samples, "aod": r.aod_rad, "n_detected": r.detected.sum(axis=1)}
        fa_int = self._interference_false_alarms(ep, b)
        dec["search"] = ep.clock("search", lambda: self.rx_exact(upsample(b.z["production"], d), s_min, n1, n2))
        dec["exact"] = ep.clock("exact", lambda: self.rx_exact(upsample(b.z["exact"], d), s_min, n1, n2))
        return dec, detector, fa_int

    def _interference_false_alarms(self, ep: _EpochInputs, b: _Bursts) -> dict[str, int]:
        """Blocks each receiver detects for the anchor cell's PCI with the anchor silent."""
        d, d_c = self.scn.receiver.decimation, self.rx.decimation
        # interference only: the anchor cell (the list's first) silent, its PCI still searched
        keep = np.asarray(ep.link_rrh) != ep.cand[0]
        sub = _subset_links(ep.links, keep)
        d2d, draws = np.asarray(ep.lb.link_d2d_m)[keep], [dr for dr, k in zip(ep.draws, keep, strict=True) if k]
        z_int = self.fast(sub, None, noise=False, t0_s=ep.t0_s, d2d_m=d2d, draws=draws, serving=ep.serv[keep])[0]
        z_int = project(z_int, self.down) + self._edges(self.fast, ep, sub, draws, d2d, ep.serv[keep])
        n = b.n_samples
        z_int = z_int[:n] if z_int.size >= n else np.pad(z_int, (0, n - z_int.size))
        return {
            name: int(r.detected.sum())
            for name, r in self.rx(upsample(z_int + b.noise, d // d_c), b.s_min, ep.n1[:1], ep.n2[:1]).items()
        }

    def _truth(self, ep: _EpochInputs) -> dict:
        """The train's state and the candidates' true distance and AOD, for scoring only."""
        dep, lb, cand, x = self.scn.deployment, ep.lb, ep.cand, ep.x_m
        inr = np.isin(cand, lb.rrh)
        pos = np.searchsorted(lb.rrh, cand[inr])
        d3d = dep.distance_3d_m(np.full(cand.size, x), cand)
        aod = dep.aod_rad(np.full(cand.size, x), cand)
        d3d[inr], aod[inr] = lb.d3d_m[pos], lb.aod_rad[pos]
        p_all = 10 ** (lb.rx_power_dbm / 10)
        return dict(
            x=x,
            v=ep.v_m_s,
            a=ep.a_m_s2,
            d3d=d3d,
            aod=aod,
            in_range=inr,
            n_links=ep.links.n,
            sir_db=10 * np.log10(p_all.max() / (p_all.sum() - p_all.max())),
        )

    def _at_train(self, n: int, serv: NDArray[np.bool_]) -> NDArray[np.bool_]:
        """The links whose data go toward the train under the scenario's traffic policy."""
        dbm = self.scn.data_beam
        if dbm == "train":
            return np.ones(n, dtype=bool)
        return serv if dbm == "serving" else np.zeros(n, dtype=bool)


def _subset_links(links, keep: NDArray[np.bool_]):
    """The :class:`railradio.nr.channel.link.Links` of the links ``keep`` marks."""
    arrays = {f.name: getattr(links, f.name) for f in dataclasses.fields(links)}
    out = {k: (v[keep] if isinstance(v, np.ndarray) and v.shape[:1] == keep.shape else v) for k, v in arrays.items()}
    return type(links)(**out)


def sample_epochs(n_run: int, n: int, change_epochs: NDArray, speed_m_s: NDArray) -> NDArray[np.int64]:
    """``n`` epochs of a run of ``n_run``: the acceleration changes (``change_epochs``, those
    inside the run) and the epoch of the highest speed, the rest spread evenly from the first
    epoch to the last (a rule fixed before any result).

    Parameters
    ----------
    n_run : int
        Epochs of the run.
    n : int
        Epochs to pick, in ``1..n_run``.
    change_epochs : numpy.ndarray
        Epochs of the acceleration changes (:func:`railradio.nr.tracking.bounds.change_epochs`).
    speed_m_s : numpy.ndarray
        [epoch] true speed, m/s.

    Returns
    -------
    numpy.ndarray of int64
        ``n`` distinct epoch indices, increasing.

    Raises
    ------
    ValueError
        When ``n`` is outside ``1..n_run``.
    """
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


PRODUCTION_AOD_TOL_RAD = 1e-5
"""How far the main run's AOD (the burst engine's) may lie from the reference receivers' on
the same burst, rad: the float32 rounding of the beam weights, the front end and the
correlation moves an AOD by 1e-7 to 1.2e-6 rad (measured, engine against reference, on r0's
epochs 580–594 with the front end's padded period), so ten times that: 6e-4°, against the
0.1° at which the target counts an AOD as changed."""


def check_production(res: dict, main_row, receivers: list[str]) -> None:
    """Raise when the production path re-run here (``own_noise``: its own draws) differs from
    the main run's estimates at that epoch (``main_row``: one epoch of its shards) — the
    comparisons would then not be about the production path.

    The main run measures its bursts with the burst engine (:mod:`railradio.nr.engine`), this
    target with the reference receivers (:class:`railradio.nr.study.fidelity_receivers.Receivers`)
    on the reference front end: the same decisions, the arithmetic differing by float32
    rounding. So TOAs must agree to 1e-6 full-rate samples and AODs to
    :data:`PRODUCTION_AOD_TOL_RAD` — on every epoch of the target, which makes it the engine's
    equivalence check on the target's epochs too.

    Parameters
    ----------
    res : dict
        One epoch's result of :meth:`FidelityRun.epoch` (with ``own_noise`` decisions).
    main_row : xarray.Dataset
        The main run's estimates at that epoch (``toa_hat`` [s], ``aod_hat`` [rad], per receiver).
    receivers : list of str
        Receiver names, in the order of ``main_row``'s ``receiver`` dim.

    Raises
    ------
    ValueError
        When a receiver's TOA (beyond 1e-6 samples) or AOD (beyond
        :data:`PRODUCTION_AOD_TOL_RAD`) differs from the main run's.
    """
    from railradio.nr.waveform.numerology import SAMPLE_RATE_HZ as FS

    for j, r in enumerate(receivers):
        d = res["decisions"]["own_noise"][r]
        toa = main_row["toa_hat"].values[j] * FS
        aod = main_row["aod_hat"].values[j]
        if not (
            np.allclose(d.toa_samples, toa, rtol=0, atol=1e-6, equal_nan=True)
            and np.allclose(d.aod_rad, aod, rtol=0, atol=PRODUCTION_AOD_TOL_RAD, equal_nan=True)
        ):
            raise ValueError(
                f"epoch {res['epoch']}, receiver {r}: the production path differs from the main run's "
                f"estimates (TOA {d.toa_samples} vs {toa})"
            )
