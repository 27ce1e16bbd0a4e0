"""The nr study's scenario and its reference epoch path: channel, received burst, per-cell
estimates.

:class:`Scenario` holds one realization's settings (:func:`scenario_from_config` builds it
from the config). Synthesis (truth -> burst, :class:`Synthesis`) and estimation (burst ->
measurements, :class:`Estimator`) are separate: the estimator never receives the truth.
Every random draw is keyed by (realization, epoch) or (realization, RRH), and the receiver's
state restarts at fixed acquisition epochs. The study runs these through the burst engine
(:mod:`railradio.nr.engine`, :func:`railradio.nr.engine.epochs.simulate_epochs`), which gives their
decisions on the same draws; the classes here are the reference that the engine, the
fidelity target and the tests are held to.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.channel.antenna import RrhArray, TrainArray
from railradio.nr.channel.geometry import Deployment, Trajectory
from railradio.nr.channel.link import RadioParams, ShadowingMap, link_budget
from railradio.nr.channel.tdl import tdl_profile
from railradio.nr.receiver.cellsearch import CellSearch, CellSearchConfig, correlation_key, ss_rsrp_db, warmup_start
from railradio.nr.receiver.config import ReceiverConfig
from railradio.nr.receiver.correlator import Correlator
from railradio.nr.receiver.frontend import project, upsample
from railradio.nr.synthesis.band_edges import BandEdges
from railradio.nr.synthesis.synthesizer import Synthesizer
from railradio.nr.waveform.numerology import SAMPLE_RATE_HZ
from railradio.nr.waveform.ssb import qpsk_pool
from railradio.nr.waveform.traffic import ServingCell, ServingRule
from railradio.rng import make_rng

# sub-keys below the realization's spawn key
KEY_SHADOWING, KEY_POOL, KEY_EPOCH = 1, 2, 3


@dataclass(frozen=True)
class Scenario:
    """Everything that defines one realization of the nr study (SI units).

    Attributes
    ----------
    trajectory : Trajectory
        The train's motion (epochs ``dt_s`` apart).
    deployment : Deployment
        RRH positions along the track and their cell IDs.
    radio : RadioParams
        Link-budget parameters (powers dBm, noise figure dB, carrier Hz, ...).
    rrh_array, train_array : RrhArray, TrainArray
        The RRH and train antenna arrays.
    receiver : ReceiverConfig
        The "source" receiver (front-end decimation, SS-block pattern, TOA settings).
    tdl : str
        3GPP TDL profile name (e.g. ``"TDL-D"``).
    delay_spread_s : float
        RMS delay spread of the TDL profile, s.
    detector : str
        Detector of the source receiver.
    pfa : float
        False-alarm probability per block of the detectors (1).
    cell_search : CellSearchConfig
        The receiver's cell search.
    n_sinusoids : int
        Sinusoids per tap of the sum-of-sinusoids fading.
    pool_size : int
        QPSK data symbols drawn once per realization for the data resource elements.
    shadowing : bool
        Whether the shadowing map is applied.
    exact_spill : bool
        Each delayed tap's copy of a symbol spills into the next symbol's first samples, as in
        the exact reference, instead of being wrapped within its own symbol (the wrapped path
        is measured by ``nr.fidelity.spill``). The study's config sets it
        (``nr.channel.exact_spill``, default true).
    """

    trajectory: Trajectory
    deployment: Deployment = field(default_factory=Deployment)
    radio: RadioParams = field(default_factory=RadioParams)
    rrh_array: RrhArray = field(default_factory=RrhArray)
    train_array: TrainArray = field(default_factory=TrainArray)
    receiver: ReceiverConfig = field(default_factory=ReceiverConfig)
    tdl: str = "TDL-D"
    delay_spread_s: float = 20e-9
    detector: str = "source"
    pfa: float = 1e-3
    extra_receivers: tuple = ()
    """Extra receivers run on the same bursts: ((name, ReceiverConfig, detector), ...);
    they must share the decimation and SS-block pattern of ``receiver``."""
    cell_search: CellSearchConfig = field(default_factory=CellSearchConfig)
    full_channel_range_m: float = np.inf
    """RRHs farther than this (2-D) are synthesized as one non-fading tap (inf: none)."""
    exact_spill: bool = False
    """Each delayed tap's copy of a symbol spills into the next symbol's first samples, as in
    the exact reference (:meth:`railradio.nr.synthesis.spill.Spill.add`), instead of
    being wrapped within its own symbol (the shortcut measured by ``nr.fidelity.spill``). The
    study's config sets it (``nr.channel.exact_spill``, default true)."""
    band_edges: bool = False
    """Add the full band's symbol edges inside the front end's band to the band synthesis
    (:class:`railradio.nr.synthesis.band_edges.BandEdges`): the burst the front end sees is then the
    full band's (``nr.channel.band_edges``, default true)."""
    synthesis_decimation: int | None = None
    """The bursts are synthesized at F_s/D_s (the central N_FFT/D_s subcarriers) and brought
    to the receiver's front end F_s/D (``receiver.decimation``) by its ideal anti-aliasing
    filter (:func:`railradio.nr.receiver.frontend.project`); ``None``: synthesized at the front end's
    rate."""
    search_decimation: int | None = None
    """The receivers' correlation lag grid F_s/D_c (finer than the front end's F_s/D of
    ``receiver.decimation``: its samples band-limited-interpolated, the templates
    zero-stuffed, :class:`railradio.nr.receiver.correlator.Correlator`); ``None``: the front end's."""
    n_sinusoids: int = 16
    pool_size: int = 256
    shadowing: bool = True
    data_beam: str = "serving"
    """Where the data go: serving | train | random | none (:class:`Synthesizer`)."""
    load: float = 1.0
    """Share of slots in which a non-serving RRH sends data (source: full buffer)."""
    serving: ServingRule = field(default_factory=ServingRule)
    """The network's serving-cell rule (:mod:`railradio.nr.waveform.traffic`)."""

    @cached_property
    def profile(self):
        """The TDL profile ``tdl`` scaled to ``delay_spread_s``
        (:class:`railradio.nr.channel.tdl.TdlProfile`).
        """
        return tdl_profile(self.tdl, self.delay_spread_s)


@dataclass
class Burst:
    """One epoch's received burst — the receiver's front-end samples at F_s/D — and the truth
    it was synthesized from (the truth is for scoring: :class:`Estimator` never receives it)."""

    z: np.ndarray
    s_min: int
    x_m: float
    v_m_s: float
    a_m_s2: float
    links: object  # railradio.nr.channel.link.LinkBudget
    serving: int = -1
    """The network's serving RRH (truth: the receiver does not know it)."""


class Synthesis:
    """Truth -> received burst, epoch by epoch; every draw keyed by (realization, epoch).

    Parameters
    ----------
    scn : Scenario
        The scenario.
    seed : int
        The config seed.
    key : tuple of int
        The realization's spawn key (:func:`railradio.rng.spawn_key`).

    Raises
    ------
    ValueError
        When ``scn.synthesis_decimation`` does not divide the front end's decimation.
    """

    def __init__(self, scn: Scenario, seed: int, key: tuple[int, ...]):
        self.scn, self.seed, self.key = scn, seed, key
        self.shadow = ShadowingMap(seed, key + (KEY_SHADOWING,), scn.deployment, scn.radio)
        pool = qpsk_pool(make_rng(seed, key + (KEY_POOL,)), scn.pool_size)
        d_fe = scn.receiver.decimation
        d_s = d_fe if scn.synthesis_decimation is None else int(scn.synthesis_decimation)
        if d_s > d_fe or d_fe % d_s:
            raise ValueError(f"synthesis_decimation must divide the front end's decimation {d_fe}, got {d_s!r}")
        self.down = d_fe // d_s  # synthesis rate -> the front end's
        self.syn = Synthesizer(
            dataclasses.replace(scn.receiver, decimation=d_s),
            scn.profile,
            pool,
            scn.n_sinusoids,
            scn.full_channel_range_m,
            scn.data_beam,
            scn.load,
            exact_spill=scn.exact_spill,
        )
        self.edges = BandEdges(self.syn, pool, d_fe) if scn.band_edges and self.down > 1 else None
        self.network = ServingCell(scn.serving)
        self.next_epoch: int | None = None

    def advance(self, epoch: int):
        """The truth of ``epoch`` and the network's serving cell there (no waveform):
        ``(x, v, a, link budget, serving RRH)``.

        Parameters
        ----------
        epoch : int
            Epoch index (t = epoch · ``trajectory.dt_s``). A jump from the last epoch resets the
            network's serving-cell state.

        Returns
        -------
        tuple
            ``(x_m, v_m_s, a_m_s2, link budget, serving RRH)``: position along the track in m, speed
            in m/s, acceleration in m/s², the :class:`railradio.nr.channel.link.LinkBudget`, and the serving
            RRH index (int).
        """
        scn = self.scn
        if self.next_epoch is not None and epoch != self.next_epoch:
            self.network.reset()
        self.next_epoch = int(epoch) + 1
        t = epoch * scn.trajectory.dt_s
        x, v, a = (float(u[0]) for u in scn.trajectory.state(np.array([t])))
        lb = link_budget(x, v, scn.deployment, scn.radio, scn.rrh_array, scn.train_array, self.shadow, scn.shadowing)
        return x, v, a, lb, self.network.update(epoch, lb.rrh, lb.rx_power_dbm)

    def __call__(self, epoch: int) -> Burst:
        """The received burst of ``epoch`` and its truth.

        Parameters
        ----------
        epoch : int
            Epoch index (t = epoch · ``trajectory.dt_s``).

        Returns
        -------
        Burst
            The front end's samples at F_s/D (complex64) with ``s_min`` and the truth.
        """
        x, v, a, lb, serving = self.advance(epoch)
        t = epoch * self.scn.trajectory.dt_s
        link_rrh = lb.rrh if lb.link_rrh is None else lb.link_rrh
        rng = make_rng(self.seed, self.key + (KEY_EPOCH, int(epoch)))
        draws = self.syn.draws(lb.links, rng)  # first, as the synthesizer would: the same stream
        serv = np.asarray(link_rrh) == serving
        z, s_min = self.syn(lb.links, rng, t0_s=t, d2d_m=lb.link_d2d_m, serving=serv, draws=draws)
        z = project(z, self.down)  # the receiver's front end
        if self.edges is not None:  # what the band leaves out there
            z += self.edges(lb.links, draws, t, lb.link_d2d_m, serv, gains=self.syn.kept_gains)
        return Burst(z, s_min, x, v, a, lb, serving)


@dataclass
class EpochEstimates:
    """What the receiver measured at one epoch: its candidate list and, per receiver and
    candidate, the correlation estimates (arrays [n_receivers, n_candidates])."""

    cand: np.ndarray
    acquired: bool
    ss_rsrp_db: np.ndarray
    aod_rad: np.ndarray
    toa_s: np.ndarray
    peak: np.ndarray
    best_score: np.ndarray
    n_detected: np.ndarray
    corr: np.ndarray | None = None


class Estimator:
    """Burst + deployment + the receiver's own state -> measurements (no truth).

    The cell search (:mod:`railradio.nr.receiver.cellsearch`) names the candidate RRHs; every
    receiver of the scenario correlates the same list. A receiver whose correlation settings
    equal the cell search's provides the search's statistics (one correlation, not two).
    """

    def __init__(self, scn: Scenario):
        """One correlator per receiver and the cell search (sharing a receiver's correlator when
        the settings match).

        Parameters
        ----------
        scn : Scenario
            The scenario (receivers, cell search, deployment; its truth is never read).

        Raises
        ------
        ValueError
            When an extra receiver differs from ``scn.receiver`` in decimation or SS-block
            pattern, or ``scn.search_decimation`` does not divide the front end's decimation.
        """
        self.scn = scn
        self.receivers = [("source", scn.receiver, scn.detector)] + list(scn.extra_receivers)
        for _, rc, _ in self.receivers:
            if rc.decimation != scn.receiver.decimation or rc.ssb_pattern != scn.receiver.ssb_pattern:
                raise ValueError("extra receivers must share decimation and ssb_pattern")
        d_fe = scn.receiver.decimation
        d_c = d_fe if scn.search_decimation is None else int(scn.search_decimation)
        if d_c > d_fe or d_fe % d_c:
            raise ValueError(f"search_decimation must divide the front end's decimation {d_fe}, got {d_c!r}")
        self.up = d_fe // d_c  # the front end's samples interpolated to the lag grid

        def cor(rc, det, pfa):
            return Correlator(dataclasses.replace(rc, decimation=d_c), det, pfa, template_decimation=d_fe)

        self.cors = [cor(rc, det, scn.pfa) for _, rc, det in self.receivers]
        cs = scn.cell_search
        cs_rc = cs.receiver_config(scn.receiver)
        cs_key = correlation_key(cs_rc, cs.detector, cs.pfa)
        self.cs_shared = next(
            (j for j, (_, rc, det) in enumerate(self.receivers) if correlation_key(rc, det, scn.pfa) == cs_key), None
        )
        cs_cor = self.cors[self.cs_shared] if self.cs_shared is not None else cor(cs_rc, cs.detector, cs.pfa)
        self.search = CellSearch(cs, scn.deployment, cs_cor)
        self.n_id1, self.n_id2 = scn.deployment.n_id()
        self.next_epoch: int | None = None

    def start(self, epoch: int) -> int:
        """The first epoch to process before reporting ``epoch`` (state reset there when a
        fixed acquisition epoch lies between the last processed epoch and ``epoch``).

        Parameters
        ----------
        epoch : int
            The epoch to report.

        Returns
        -------
        int
            The epoch to start from: the earlier of the last fixed acquisition and serving-cell
            reset epochs at or before ``epoch`` (the search reset), or the next unprocessed epoch.
        """
        w = min(
            warmup_start(epoch, self.scn.cell_search.acquire_every), warmup_start(epoch, self.scn.serving.reset_every)
        )
        if self.next_epoch is None or w >= self.next_epoch or epoch < self.next_epoch:
            self.search.reset()
            return w
        return self.next_epoch

    def __call__(
        self, epoch: int, z: np.ndarray, s_min: int, report: bool = True, keep_corr: bool = False
    ) -> EpochEstimates | None:
        """Measure one epoch; ``report=False`` (a replayed warm-up epoch) runs the cell
        search only.

        Parameters
        ----------
        epoch : int
            Epoch index.
        z : numpy.ndarray of complex64
            The burst's front-end samples at F_s/D, [n_samples].
        s_min : int
            Symbol index of the burst's first sample.
        report : bool
            Correlate every receiver and return the estimates.
        keep_corr : bool
            Keep the source receiver's per-block correlation (``corr``).

        Returns
        -------
        EpochEstimates or None
            The neighbour list and its SS-RSRP [dB, arbitrary reference], [n_cand]; per receiver
            AOD [rad], TOA [s], peak, best score, detected blocks, [n_receivers, n_cand]; None when
            ``report`` is False.
        """
        if self.next_epoch is not None and epoch != self.next_epoch:
            self.search.reset()
        self.next_epoch = int(epoch) + 1
        z = upsample(z, self.up)  # the front end's samples on the receivers' lag grid
        spectra = {}  # window FFTs shared by correlators with the same window length

        def zf(cor):
            if cor.n_win not in spectra:
                spectra[cor.n_win] = cor.window_spectra(z, s_min)
            return spectra[cor.n_win]

        cs_cor = self.search.correlator
        cand, acquired = self.search.candidates(epoch, z, s_min, zf(cs_cor))
        n1, n2 = self.n_id1[cand], self.n_id2[cand]
        results = {}
        if self.cs_shared is None or not report:
            cs_res = cs_cor.correlate(z, s_min, n1, n2, zf=zf(cs_cor))
        if report:
            for j, cor in enumerate(self.cors):
                results[j] = cor.correlate(z, s_min, n1, n2, keep_corr=(j == 0 and keep_corr), zf=zf(cor))
            if self.cs_shared is not None:
                cs_res = results[self.cs_shared]
        rsrp = ss_rsrp_db(cs_res)
        self.search.update(cand, rsrp)
        if not report:
            return None
        n_r, n_c = len(self.cors), cand.size
        out = EpochEstimates(
            cand, acquired, rsrp, *(np.full((n_r, n_c), np.nan) for _ in range(4)), np.zeros((n_r, n_c), dtype=np.int64)
        )
        for j, res in results.items():
            out.aod_rad[j] = res.aod_rad
            out.toa_s[j] = res.toa_samples / SAMPLE_RATE_HZ
            out.peak[j] = res.peak_comb
            out.n_detected[j] = res.detected.sum(axis=1)
            score = np.where(res.detected, (res.eta - res.mu) / np.maximum(res.sigma, 1e-30), -np.inf)
            out.best_score[j] = np.where(res.detected.any(axis=1), score.max(axis=1), np.nan)
        if keep_corr:
            out.corr = results[0].corr
        return out


def scenario_from_config(c: dict) -> Scenario:
    """Build the :class:`Scenario` from the ``nr`` section of the workflow config.

    Parameters
    ----------
    c : dict
        The ``nr`` section of the config (or a case's merged config): sections ``trajectory``,
        ``deployment``, ``radio``, ``antenna``, ``channel``, ``receiver``, ``traffic`` and the
        optional ``cell_search`` and ``extra_receivers``, in the config's SI units.

    Returns
    -------
    Scenario
        The scenario; ``receiver.search_range_m`` becomes the lag window ceil(range / c · F_s).
    """
    from railradio.nr.channel.antenna import RrhArray, TrainArray

    rx = c["receiver"]
    # [ours] search window bounded by the geometry: lags covering delays up to range / c
    search_lags = (
        None
        if rx.get("search_range_m") is None
        else int(np.ceil(rx["search_range_m"] / SPEED_OF_LIGHT_M_S * SAMPLE_RATE_HZ))
    )
    return Scenario(
        trajectory=_trajectory(c["trajectory"]["phases"], c["trajectory"]["dt_s"]),
        deployment=Deployment(**{k: float(v) for k, v in c["deployment"].items()}),
        radio=RadioParams(**{k: float(v) for k, v in c["radio"].items()}),
        rrh_array=RrhArray(n_elements=int(c["antenna"]["rrh_elements"]), n_beams=int(c["antenna"]["n_beams"])),
        train_array=TrainArray(
            n_elements=int(c["antenna"]["train_elements"]),
            panel_x_m=tuple(float(v) for v in c["antenna"].get("train_panels_x_m", (0.0, 0.0))),
        ),
        receiver=ReceiverConfig(
            decimation=int(rx["decimation"]),
            ssb_pattern=rx["ssb_pattern"],
            n_blocks=int(c["antenna"]["n_beams"]),
            toa_blocks=rx["toa_blocks"],
            subsample=bool(rx["subsample"]),
            template=rx["template"],
            search_lags=search_lags,
        ),
        tdl=c["channel"]["tdl"],
        delay_spread_s=float(c["channel"]["delay_spread_s"]),
        detector=rx["detector"],
        pfa=float(rx["pfa"]),
        cell_search=CellSearchConfig(**c.get("cell_search", {})),
        extra_receivers=tuple(
            (
                name,
                ReceiverConfig(
                    decimation=int(rx["decimation"]),
                    ssb_pattern=rx["ssb_pattern"],
                    n_blocks=int(c["antenna"]["n_beams"]),
                    toa_blocks=v["toa_blocks"],
                    subsample=bool(v["subsample"]),
                    template=v["template"],
                    search_lags=search_lags,
                ),
                v["detector"],
            )
            for name, v in c.get("extra_receivers", {}).items()
        ),
        full_channel_range_m=(
            np.inf if c["channel"]["full_channel_range_m"] is None else float(c["channel"]["full_channel_range_m"])
        ),
        synthesis_decimation=int(c["channel"].get("synthesis_decimation", rx["decimation"])),
        exact_spill=bool(c["channel"].get("exact_spill", False)),
        band_edges=bool(c["channel"].get("band_edges", False)),
        search_decimation=int(rx.get("search_decimation", rx["decimation"])),
        n_sinusoids=int(c["channel"]["n_sinusoids"]),
        data_beam=c["traffic"]["data_beam"],
        load=float(c["traffic"]["load"]),
        serving=ServingRule(float(c["traffic"]["serving_hysteresis_db"]), int(c["traffic"]["serving_reset_every"])),
    )


def calibration_trajectory(c: dict) -> Trajectory:
    """The calibration run's own trajectory (``calibration.trajectory`` of the ``nr``
    config), sampled at the evaluation's ``trajectory.dt_s``.

    Parameters
    ----------
    c : dict
        The ``nr`` section of the config: ``calibration.trajectory.phases``
        ([[duration s, acceleration m/s²], ...]), optional ``v0_m_s`` (m/s) and ``trajectory.dt_s`` (s).

    Returns
    -------
    Trajectory
        The calibration trajectory.
    """
    tr = c["calibration"]["trajectory"]
    return _trajectory(tr["phases"], c["trajectory"]["dt_s"], tr.get("v0_m_s", 0.0))


def _trajectory(phases, dt_s, v0_m_s: float = 0.0) -> Trajectory:
    """A :class:`Trajectory` from config phases ``[[duration s, acceleration m/s²], ...]``
    and a start speed [m/s]."""
    return Trajectory(tuple(tuple(map(float, p)) for p in phases), float(dt_s), v0_m_s=float(v0_m_s))
