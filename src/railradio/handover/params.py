"""Parameters of the handover study (docs/model/handover.md).

The source (Zhang, Li, Xie 2022) lost every equation and its Table 1; the model is OUR
reconstruction.  Every value lives in the ``handover`` section of the config; this module
turns that section into frozen dataclasses with SI units and checks every value, raising
:class:`ValueError` naming the parameter.  Tags in the docstrings: [source], [3GPP], [ours].
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from typing import Any

from railradio.handover.rlm import RlmConfig

KMH = 1.0 / 3.6
"""m/s per km/h."""


def _check(
    name: str,
    value: float,
    lo: float | None = None,
    hi: float | None = None,
    lo_open: bool = False,
    hi_open: bool = False,
) -> None:
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    if lo is not None and (value <= lo if lo_open else value < lo):
        raise ValueError(f"{name} must be {'>' if lo_open else '>='} {lo}, got {value!r}")
    if hi is not None and (value >= hi if hi_open else value > hi):
        raise ValueError(f"{name} must be {'<' if hi_open else '<='} {hi}, got {value!r}")


def _check_l3_k(value) -> None:
    if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value <= 19:
        raise ValueError(f"l3_k must be an integer in 0..19 (TS 36.331), got {value!r}")


def _choice(name: str, value: str, allowed: tuple[str, ...]) -> None:
    if value not in allowed:
        raise ValueError(f"{name} must be one of {allowed}, got {value!r}")


@dataclass(frozen=True)
class Radio:
    """Two cells along a straight track and their radio links (reconstruction eq. 1–2).

    spacing_m
        eNB/RRH spacing L_BS [m] [source: 1.5–2.0 km]; serving at x_s = 0, target at L_BS.
    offset_m
        RRH distance from the track h [m] [ours].
    carrier_hz, tx_power_dbm, bandwidth_hz, noise_figure_db
        1.8 GHz, 46 dBm, 10 MHz, 7 dB [ours]; thermal noise −174 dBm/Hz.
    ref_distance_m
        d0 of the log-distance law; L(d0) is the free-space loss at d0 [ours].
    pathloss_exponent
        n [source: 2–6, mountain scenario; 3.5 ours].
    shadow_sigma_db, shadow_corr_m
        σ of the shadowing ζ and its decorrelation distance (AR(1) in distance): 4 dB and
        40 m, WINNER II D1.1.2 scenario D2a (a base station to a relay on a high-speed train,
        rural LOS, Table 4-5) [WINNER II].
    shadow_cross_corr
        correlation of the two links' shadowing [ours: 0].
    shadow_grid_m
        spacing of the grid the shadowing field is drawn on; a position takes the nearest
        grid value (numerics only).
    meas_sigma_db
        residual fading of one RSRP measurement σ_m [ours].
    meas_period_s
        measurement period T_m [ours: 40 ms].
    l3_k
        TS 36.331 filterCoefficient k (a = 1/2^(k/4) at 200 ms) [3GPP].
    l3_reference_period_s
        the sample period k refers to (TS 36.331 §5.5.3.2: 200 ms) [3GPP].
    load_factor
        η, the other cell's load (interference weight) [ours].
    q_out_db, q_in_db
        SINR thresholds of the serving link at the command and the target at access [ours].
    antenna_hpbw_deg, antenna_max_loss_db
        the RRHs' antennas point along the track, one each way (railway practice): TR 38.901
        Table 7.3-1's pattern, 65° half-power beamwidth, 30 dB floor [3GPP]; ``tx_power_dbm``
        is the EIRP on boresight; ``None``: omnidirectional.
    sfn_rrhs
        RRHs per cell [ours: 1]: with K > 1 each cell is a single-frequency network of K RRHs
        every ``spacing_m`` along the line, one cell ID (TS 36.101 Annex B.3A, HST-SFN): the
        serving cell's at x_s − k·L_BS, the target's at x_t + k·L_BS (k < K), each with its own
        shadowing field; a cell's local mean is the power sum of its RRHs'.
    fading, fading_k_db
        fast fading where one look decides (the PRACH occasions of the ``stages`` rule,
        :mod:`railradio.handover.fading`): ``rician`` with K-factor ``fading_k_db``
        [3GPP TR 38.901 Table 7.5-6, RMa LOS μ_K = 7 dB], ``rayleigh``, or ``none``.
    """

    spacing_m: float = 1500.0
    offset_m: float = 30.0
    carrier_hz: float = 1.8e9
    tx_power_dbm: float = 46.0
    bandwidth_hz: float = 1.0e7
    noise_figure_db: float = 7.0
    ref_distance_m: float = 100.0
    pathloss_exponent: float = 3.5
    shadow_sigma_db: float = 4.0
    shadow_corr_m: float = 40.0
    shadow_cross_corr: float = 0.0
    shadow_grid_m: float = 0.5
    meas_sigma_db: float = 1.5
    meas_period_s: float = 0.04
    l3_k: int = 4
    l3_reference_period_s: float = 0.2
    load_factor: float = 0.5
    q_out_db: float = -8.0
    q_in_db: float = -6.0
    fading: str = "rician"
    fading_k_db: float = 7.0
    antenna_hpbw_deg: float | None = 65.0
    antenna_max_loss_db: float = 30.0
    sfn_rrhs: int = 1

    def __post_init__(self) -> None:
        _check("spacing_m", self.spacing_m, 10.0, 1e5)
        _check("offset_m", self.offset_m, 0.0, 1e3)
        _check("carrier_hz", self.carrier_hz, 1e6, 1e12)
        _check("tx_power_dbm", self.tx_power_dbm, -50.0, 100.0)
        _check("bandwidth_hz", self.bandwidth_hz, 0.0, 1e10, lo_open=True)
        _check("noise_figure_db", self.noise_figure_db, 0.0, 30.0)
        _check("ref_distance_m", self.ref_distance_m, 0.0, 1e4, lo_open=True)
        _check("pathloss_exponent", self.pathloss_exponent, 1.0, 8.0)
        _check("shadow_sigma_db", self.shadow_sigma_db, 0.0, 20.0)
        _check("shadow_corr_m", self.shadow_corr_m, 0.0, 1e4, lo_open=True)
        _check("shadow_cross_corr", self.shadow_cross_corr, -1.0, 1.0)
        _check("shadow_grid_m", self.shadow_grid_m, 0.0, 10.0, lo_open=True)
        _check("meas_sigma_db", self.meas_sigma_db, 0.0, 20.0)
        _check("meas_period_s", self.meas_period_s, 0.0, 1.0, lo_open=True)
        _check_l3_k(self.l3_k)
        _check("l3_reference_period_s", self.l3_reference_period_s, 0.0, 10.0, lo_open=True)
        _check("load_factor", self.load_factor, 0.0, 1.0)
        _check("q_out_db", self.q_out_db, -30.0, 30.0)
        _check("q_in_db", self.q_in_db, -30.0, 30.0)
        _choice("fading", self.fading, ("none", "rayleigh", "rician"))
        _check("fading_k_db", self.fading_k_db, -30.0, 40.0)
        if self.antenna_hpbw_deg is not None:
            _check("antenna_hpbw_deg", self.antenna_hpbw_deg, 1.0, 180.0)
        _check("antenna_max_loss_db", self.antenna_max_loss_db, 0.0, 60.0)
        if not isinstance(self.sfn_rrhs, int) or isinstance(self.sfn_rrhs, bool) or not 1 <= self.sfn_rrhs <= 8:
            raise ValueError(f"sfn_rrhs must be an integer in 1..8, got {self.sfn_rrhs!r}")

    @property
    def x_serving_m(self) -> float:
        return 0.0

    @property
    def x_target_m(self) -> float:
        return self.spacing_m

    @property
    def overlap_centre_m(self) -> float:
        """Xc = x_s + L_BS/2."""
        return 0.5 * self.spacing_m


@dataclass(frozen=True)
class Train:
    """The train and its position input.

    n_nodes, node_spacing_m
        N roof relay-AP nodes, node 1 at the head [ours: 8 × 25 m].
    gnss_sigma_m, gnss_bound_m, gnss_corr_s
        GNSS/INS along-track error: first-order Gauss–Markov with correlation time
        gnss_corr_s, std gnss_sigma_m, truncated (clipped) at ±gnss_bound_m [source: < 5 m;
        σ 2 m and 1 s ours].
    prep_zone_m
        preparation starts within this distance of the overlap centre [source: 500 m].
    """

    n_nodes: int = 8
    node_spacing_m: float = 25.0
    gnss_sigma_m: float = 2.0
    gnss_bound_m: float = 5.0
    gnss_corr_s: float = 1.0
    prep_zone_m: float = 500.0

    def __post_init__(self) -> None:
        if not isinstance(self.n_nodes, int) or isinstance(self.n_nodes, bool) or not 1 <= self.n_nodes <= 64:
            raise ValueError(f"n_nodes must be an integer in 1..64, got {self.n_nodes!r}")
        _check("node_spacing_m", self.node_spacing_m, 0.0, 500.0)
        _check("gnss_sigma_m", self.gnss_sigma_m, 0.0, 100.0)
        _check("gnss_bound_m", self.gnss_bound_m, 0.0, 1000.0)
        _check("gnss_corr_s", self.gnss_corr_s, 0.0, 1e4, lo_open=True)
        _check("prep_zone_m", self.prep_zone_m, 0.0, 1e5, lo_open=True)


@dataclass(frozen=True)
class Execution:
    """Handover execution (reconstruction eq. 3 and 8).

    t0_s
        fixed execution delay T0: He = Hb + v·T0 [source eq. 2]; 30 ms = RRC processing
        15 ms (TS 36.331 §11.2) + random access 10 ms + path switch 5 ms [ours].
    tz_s
        interval before a second attempt TZ [source: 50 ms].
    max_attempts
        attempts of every policy: a failed attempt is followed by another after TZ while
        the serving link holds, up to this many [source eq. 9: one second attempt, so 2].
    retry
        ``common`` (the default): that rule for every policy; ``joint_band``: the earlier
        joint-only rule as a case — the joint policy makes one second attempt whenever its
        execution (or completion, ``joint.retry_rule``) lies before PR, whether or not the
        serving link holds; A3 and distance keep the common rule.
    pingpong_window_s
        a handover back to the previous cell within this time of completion is a
        ping-pong [TR 36.839's minimum time of stay, 1 s].
    failure_rule
        when a handover fails.  ``stages`` (the default): the procedure's failure stages,
        each on its own link (:mod:`railradio.handover.stages`: the command lost while the
        serving link's T310 runs, access at the PRACH occasions while T304 runs, radio-link
        failure on the new link shortly after completion; outcomes too late / too early /
        other, TS 36.300 §22.4.2.2, TR 36.839 §5.2.1); one attempt, a failure goes to
        re-establishment (``max_attempts``, ``tz_s`` and ``retry`` apply to the other rules).
        ``rlm`` (the earlier 3GPP-based rule, a case): radio-link
        monitoring (:mod:`railradio.handover.rlm`: indications every ``rlm_indication_s``
        along the train's path from the start of the crossing, out-of-sync when the
        ``rlf_eval_s`` mean of the serving SINR is below Q_out, in-sync when the
        ``rlm_qin_eval_s`` mean is above Q_in, N310/N311 and T310 = ``rlf_t310_s``,
        TS 36.133 §7.6, TS 36.331 §5.3.11); an attempt fails if radio-link failure was
        declared before its command (the command cannot be received), or if the target's
        SINR, averaged over the execution's indications (the random access while T304
        runs), is below Q_out (TR 36.839's handover-failure rule).
        ``instant`` (the earlier one-sample rule, a case): the serving local-mean SINR at
        H_b is below Q_out, or the target's at H_e below Q_in.  ``rlf`` (a case): as
        ``instant`` but the serving link fails only after a T310-long run of
        ``rlf_eval_s`` out-of-sync evaluations before the command [ours].
    rlf_t310_s, rlf_eval_s
        T310 (the out-of-sync time until radio-link failure) and the Qout evaluation period
        of one out-of-sync indication [3GPP: T310 1 s, TS 36.331 §9.2.5 default; 200 ms
        Qout evaluation, TS 36.133 §7.6].
    rlm_indication_s, rlm_qin_eval_s, rlm_n310, rlm_n311
        ``rlm`` rule: interval between indications (TS 36.213 §4.2.1: 10 ms), Qin
        evaluation period (TS 36.133 §7.6: 100 ms), N310 and N311 (TS 36.331 §9.2.5: 1, 1).
    report_delay_s
        measurement report to the command's reception: the network's handover preparation
        (every rule; the joint decision aims its band at completion ``report_delay_s + t0_s``
        after its decision).
    rrc_processing_s
        ``stages``: command reception to the first PRACH occasion (TS 36.331 §11.2: 15 ms
        for an RRCConnectionReconfiguration with mobility); the rest of ``t0_s`` is the random
        access and path switch after a successful occasion.
    ra_period_s
        ``stages``: between two PRACH occasions (one per 10 ms radio frame).
    t304_s
        ``stages``: T304, the time access may take from the command (TS 36.331 §6.3.2).
    monitor_s
        ``stages``: a T310 started on the new link within this time of completion that
        expires is a radio-link failure shortly after the handover (TS 36.300 §22.4.2.2).
    reestablish_s
        recovery after a failed handover (every attempt failed): RRC connection
        re-establishment (TS 36.331 §5.3.7) completes this long after the failure is
        detected (the radio-link failure, or the end of the last failed execution); the
        time counts in the command-to-completion delay of all handovers.  TS 36.133
        §6.1.2.1: 50 ms + T_identify (100 ms, a cell measured in the last 5 s) + T_SI +
        T_PRACH, with T_SI = 80 ms (one SIB1 period, TS 36.331 §5.2.1.2) and T_PRACH =
        10 ms (one PRACH opportunity per frame) [ours] = 240 ms.
    """

    t0_s: float = 0.030
    tz_s: float = 0.050
    max_attempts: int = 2
    retry: str = "common"
    pingpong_window_s: float = 1.0
    failure_rule: str = "stages"
    rlf_t310_s: float = 1.0
    rlf_eval_s: float = 0.2
    rlm_indication_s: float = 0.010
    rlm_qin_eval_s: float = 0.100
    rlm_n310: int = 1
    rlm_n311: int = 1
    reestablish_s: float = 0.240
    report_delay_s: float = 0.050
    rrc_processing_s: float = 0.015
    ra_period_s: float = 0.010
    t304_s: float = 0.500
    monitor_s: float = 1.0

    def __post_init__(self) -> None:
        _check("t0_s", self.t0_s, 0.0, 1.0)
        _check("tz_s", self.tz_s, 0.0, 1.0)
        if not isinstance(self.max_attempts, int) or not 1 <= self.max_attempts <= 100:
            raise ValueError(f"max_attempts must be an integer in 1..100, got {self.max_attempts!r}")
        _choice("retry", self.retry, ("common", "joint_band"))
        _check("pingpong_window_s", self.pingpong_window_s, 0.0, 60.0)
        _check("reestablish_s", self.reestablish_s, 0.0, 10.0)
        _choice("failure_rule", self.failure_rule, ("instant", "rlf", "rlm", "stages"))
        _check("report_delay_s", self.report_delay_s, 0.0, 1.0)
        _check("rrc_processing_s", self.rrc_processing_s, 0.0, self.t0_s)
        _check("ra_period_s", self.ra_period_s, 0.0, 0.1, lo_open=True)
        _check("t304_s", self.t304_s, self.rrc_processing_s, 10.0)
        _check("monitor_s", self.monitor_s, 0.0, 60.0)
        _check("rlf_t310_s", self.rlf_t310_s, 0.0, 10.0)
        _check("rlf_eval_s", self.rlf_eval_s, 0.0, 2.0, lo_open=True)
        _check("rlm_indication_s", self.rlm_indication_s, 0.0, 1.0, lo_open=True)
        _check("rlm_qin_eval_s", self.rlm_qin_eval_s, 0.0, 2.0, lo_open=True)
        for name in ("rlm_n310", "rlm_n311"):
            v = getattr(self, name)
            if not isinstance(v, int) or not 1 <= v <= 20:
                raise ValueError(f"{name} must be an integer in 1..20 (TS 36.331 §6.3.6), got {v!r}")

    @property
    def lead_s(self) -> float:
        """Decision (report) to completion when everything goes first time: the report delay
        plus T0 [s]."""
        return self.report_delay_s + self.t0_s

    def stage_times(self):
        """The ``stages`` rule's times (:class:`railradio.handover.stages.StageTimes`)."""
        from railradio.handover.stages import StageTimes

        return StageTimes(
            self.report_delay_s, self.rrc_processing_s, self.t0_s, self.ra_period_s, self.t304_s, self.monitor_s
        )

    def rlm(self, radio: Radio) -> RlmConfig:
        """The ``rlm`` rule's constants, with Q_out and Q_in from ``radio``."""
        return RlmConfig(
            indication_s=self.rlm_indication_s,
            qout_eval_s=self.rlf_eval_s,
            qin_eval_s=self.rlm_qin_eval_s,
            q_out_db=radio.q_out_db,
            q_in_db=radio.q_in_db,
            n310=self.rlm_n310,
            n311=self.rlm_n311,
            t310_s=self.rlf_t310_s,
        )


@dataclass(frozen=True)
class Joint:
    """The position-power joint decision (reconstruction eq. 5–15).

    gaph_gamma_db, gaph_kappa, gaph_rule, gaph_floor_db
        GapH = Γ + κσ0 (``widen``) or max(Γ − κσ0, floor) (``narrow``) [ours].
    band_fit
        ``offset_exponent``: fit â and n̂ to the measured gaps; ``offset``: fit â with n known.
    exponent_bounds
        n̂ is clipped to this range [source: n in 2–6].
    min_fit_samples
        gap measurements in the zone before the band is defined [ours].
    measurements
        ``l3``: the policy uses L3-filtered RSRP (as σ0 assumes); ``raw``: single samples.
    wslr
        ``regression``: weighted linear regression over the m predecessors; ``mean``:
        their weighted mean [ours, both readings of the source's WSLR].
    m, alpha
        number of joint nodes and the geometric weight parameter; ``None`` = the cost
        grid's argmin (the source's procedure).
    dead_zone_db
        ε: |ĉ| ≤ ε gives no position correction [ours].
    retry_rule
        the second attempt must be ``executed`` (source eq. 9) or ``completed`` before PR.
    convergence_db
        a node has converged if its measured gap at the trigger is below this [source: 3 dB].
    """

    gaph_gamma_db: float = 6.0
    gaph_kappa: float = 1.0
    gaph_rule: str = "widen"
    gaph_floor_db: float = 1.0
    band_fit: str = "offset_exponent"
    exponent_bounds: tuple[float, float] = (2.0, 6.0)
    min_fit_samples: int = 5
    measurements: str = "l3"
    wslr: str = "regression"
    m: int | None = None
    alpha: float | None = None
    dead_zone_db: float = 0.5
    retry_rule: str = "executed"
    convergence_db: float = 3.0

    def __post_init__(self) -> None:
        _check("gaph_gamma_db", self.gaph_gamma_db, 0.0, 50.0, lo_open=True)
        _check("gaph_kappa", self.gaph_kappa, 0.0, 10.0)
        _choice("gaph_rule", self.gaph_rule, ("widen", "narrow"))
        _check("gaph_floor_db", self.gaph_floor_db, 0.0, 50.0, lo_open=True)
        _choice("band_fit", self.band_fit, ("offset_exponent", "offset"))
        lo, hi = self.exponent_bounds
        _check("exponent_bounds[0]", lo, 1.0, 8.0)
        _check("exponent_bounds[1]", hi, lo, 8.0)
        if not isinstance(self.min_fit_samples, int) or self.min_fit_samples < 2:
            raise ValueError(f"min_fit_samples must be an integer >= 2, got {self.min_fit_samples!r}")
        _choice("measurements", self.measurements, ("l3", "raw"))
        _choice("wslr", self.wslr, ("regression", "mean"))
        if self.m is not None and (not isinstance(self.m, int) or not 1 <= self.m <= 16):
            raise ValueError(f"m must be null or an integer in 1..16, got {self.m!r}")
        if self.alpha is not None:
            _check("alpha", self.alpha, 0.0, 1.0, lo_open=True, hi_open=True)
        _check("dead_zone_db", self.dead_zone_db, 0.0, 20.0)
        _choice("retry_rule", self.retry_rule, ("executed", "completed"))
        _check("convergence_db", self.convergence_db, 0.0, 50.0, lo_open=True)


@dataclass(frozen=True)
class A3:
    """The A3 event (TS 36.331 §5.5.4.4) [3GPP]: hysteresis, TTT, offset, and optionally its
    own L3 filter coefficient.

    hysteresis_db, ttt_s, offset_db
        Hys, TimeToTrigger and the offset of A3-1 read as Mn − Hys > Mp + ``offset_db``:
        a3-Offset minus the target's cell individual offset Ocn (a CIO of c dB toward the
        target is ``offset_db`` = −c).
    l3_k
        filterCoefficient k of the measurements this event reads (``None``: ``radio.l3_k``).
    """

    hysteresis_db: float = 3.0
    ttt_s: float = 0.16
    offset_db: float = 0.0
    l3_k: int | None = None

    def __post_init__(self) -> None:
        _check("hysteresis_db", self.hysteresis_db, 0.0, 15.0)
        _check("ttt_s", self.ttt_s, 0.0, 5.12)
        _check("offset_db", self.offset_db, -15.0, 15.0)
        if self.l3_k is not None:
            _check_l3_k(self.l3_k)


RAIL_A3 = A3(hysteresis_db=1.0, ttt_s=0.064, offset_db=-2.0, l3_k=1)
"""A3 as a railway network tunes it (the ``a3_rail`` policy) [ours: no operator publishes
its values; the rule, fixed before any result: every setting at the reactive end that the
TS 36.331 value sets and the railway practice of short triggers allow]: filterCoefficient
k = 1 (a = 0.84 at 200 ms, the shortest memory above none), TimeToTrigger 64 ms (the
TS 36.331 value inside the 40–100 ms railways use), Hys 1 dB, and a cell individual
offset of 2 dB toward the next cell along the line (``offset_db`` = −2 dB: the target needs
2 dB less to trigger). The neighbour list is one-way (only the next cell), which the
two-cell model has by construction."""


@dataclass(frozen=True)
class Scenario:
    """Everything one simulation needs except the speed and the random draws.

    Parameters
    ----------
    radio : Radio
        The two cells, their links and the measurements (SI units: m, s, Hz, dB, dBm).
    train : Train
        The train's relay-AP nodes and its GNSS/INS position input.
    execution : Execution
        Handover execution, retries, failure rule and re-establishment.
    joint : Joint
        The position-power joint decision (``m`` and ``alpha`` may be ``None`` until the
        cost grid's argmin is set with :meth:`with_weights`).
    a3 : A3
        The A3 event baseline.
    a3_rail : A3
        A3 as railways tune it (:data:`RAIL_A3`), the ``a3_rail`` policy.
    """

    radio: Radio = field(default_factory=Radio)
    train: Train = field(default_factory=Train)
    execution: Execution = field(default_factory=Execution)
    joint: Joint = field(default_factory=Joint)
    a3: A3 = field(default_factory=A3)
    a3_rail: A3 = RAIL_A3

    def with_weights(self, m: int, alpha: float) -> Scenario:
        """The same scenario with the joint policy's (m, α) set.

        Parameters
        ----------
        m : int
            Number of joint nodes whose deviations feed the WSLR, 1 ≤ m ≤ 16.
        alpha : float
            Geometric weight parameter α [1], 0 < α < 1.

        Returns
        -------
        Scenario
            A copy with ``joint.m = int(m)`` and ``joint.alpha = float(alpha)``.

        Raises
        ------
        ValueError
            If ``m`` or ``alpha`` is outside its range (from :class:`Joint`).
        """
        return replace(self, joint=replace(self.joint, m=int(m), alpha=float(alpha)))

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


SIM_SECTIONS = ("radio", "train", "execution", "joint", "a3", "a3_rail")
"""The sections of the config's ``handover`` section that make up a :class:`Scenario`."""


def scenario_from_config(cfg: dict[str, Any]) -> Scenario:
    """:class:`Scenario` from the config's ``handover`` section (or a subset of it).

    Parameters
    ----------
    cfg : dict
        Mapping with optional sub-mappings ``radio``, ``train``, ``execution``, ``joint``,
        ``a3`` and ``a3_rail`` (:data:`SIM_SECTIONS`; ``a3_rail``'s missing keys keep
        :data:`RAIL_A3`), each holding field values of the dataclass of the
        same name in its units (m, s, Hz, dB, dBm, 1); a missing section or key keeps the
        default.  ``joint.exponent_bounds`` may be a list.  Other keys of ``cfg`` are ignored.

    Returns
    -------
    Scenario
        The checked, frozen scenario.

    Raises
    ------
    ValueError
        If a value is outside its allowed range or choice set (the message names it).
    TypeError
        If a section holds a key that is not a field of its dataclass.
    """

    def sub(cls, name):
        values = dict(cfg.get(name, {}))
        if name == "joint" and "exponent_bounds" in values:
            values["exponent_bounds"] = tuple(float(v) for v in values["exponent_bounds"])
        return cls(**values)

    return Scenario(
        radio=sub(Radio, "radio"),
        train=sub(Train, "train"),
        execution=sub(Execution, "execution"),
        joint=sub(Joint, "joint"),
        a3=sub(A3, "a3"),
        a3_rail=replace(RAIL_A3, **cfg.get("a3_rail", {})),
    )


def check_speed(speed_kmh: float) -> float:
    """Speed in m/s from km/h; ValueError unless 1 ≤ v ≤ 1000 km/h."""
    _check("speed_kmh", speed_kmh, 1.0, 1000.0)
    return float(speed_kmh) * KMH
