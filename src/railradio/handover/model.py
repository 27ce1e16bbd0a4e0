"""One block of crossings: the random draws, the radio and position arrays every policy
reads, and the execution model (reconstruction eq. 1–3, 8).

Arrays are [B, N, 2, K]: runs (train crossings), nodes, links (0 serving, 1 target),
samples every T_m.  Every random number of a block comes from :func:`draw_block`, so the
vectorized engine and the per-step reference (:mod:`railradio.handover.reference`)
consume identical draws.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from railradio.handover.params import Scenario
from railradio.handover.radio import (
    ar1_coefficient,
    ar1_process,
    l3_coefficient_at,
    l3_filter,
    mean_rsrp_dbm,
    sfn_shadowing,
    shadowing_fields,
    sinr_db,
)
from railradio.handover.rlm import first_rlf, indications
from railradio.handover.train import Kinematics, gnss_error_m
from railradio.rng import make_rng, spawn_key, stable_id

STREAMS = {"sweep": (0, 1), "cost": (2, 3)}
"""Spawn-key stream IDs (field, noise) of the evaluation runs and of the separate cost-grid
runs (the weights are never selected on the runs they are evaluated on)."""

FADING_SUBSTREAM = 1
"""Sub-ID appended to a block's noise key for its fast fading (:meth:`Draws.fading`)."""

SFN_SUBSTREAM = 1
"""Sub-ID appended to a block's field key for the shadowing of the cells' other RRHs
(:meth:`Draws.sfn_white`; ``radio.sfn_rrhs`` > 1)."""


@dataclass(frozen=True)
class Draws:
    """Standard normals of one block of B crossings."""

    field_white: np.ndarray  # [B, 2, G]   shadowing field of both links along the track
    meas_white: np.ndarray  # [B, N, 2, K] measurement error per node, link, sample
    gnss_white: np.ndarray  # [B, K]       GNSS/INS error process
    fading_key: tuple | None = None  # (seed, spawn key) of the fast fading at the PRACH occasions
    sfn_key: tuple | None = None  # (seed, spawn key) of the shadowing of the cells' other RRHs

    @property
    def n_runs(self) -> int:
        return self.field_white.shape[0]

    def fading(self, n_occasions: int) -> tuple[np.ndarray, np.ndarray]:
        """The fast-fading draws of the block's handovers at ``n_occasions`` PRACH occasions
        (:mod:`railradio.handover.fading`): standard normals [B, N, 2, n_occasions, 2]
        (link; real, imaginary) and the LOS phases in turns [B, N, 2], from their own
        stream (the other draws do not depend on it)."""
        if self.fading_key is None:
            raise ValueError("these draws carry no fading_key (made without draw_block)")
        rng = make_rng(*self.fading_key)
        b_n, n_n = self.meas_white.shape[:2]
        white = rng.standard_normal((b_n, n_n, 2, int(n_occasions), 2))
        phase0 = rng.random((b_n, n_n, 2))
        return white, phase0

    def sfn_white(self, n_other: int) -> np.ndarray:
        """Standard normals of the shadowing fields of each cell's ``n_other`` RRHs beyond the
        nearest (``radio.sfn_rrhs`` − 1), [B, 2, n_other, G] float32, from their own stream keyed
        by the block like the nearest RRHs' field (the other draws do not depend on it)."""
        if self.sfn_key is None:
            raise ValueError("these draws carry no sfn_key (made without draw_block)")
        b_n, _, g_n = self.field_white.shape
        return make_rng(*self.sfn_key).standard_normal((b_n, 2, int(n_other), g_n), dtype=np.float32)


def block_keys(speed_kmh: float, block: int, stream: str = "sweep") -> tuple[tuple[int, ...], tuple[int, ...]]:
    """Spawn keys (field, noise) of one block.

    The shadowing field is keyed by the block only: every speed crosses the same fields
    (common random numbers across the sweep); measurement and GNSS noise by speed and block.
    """
    if stream not in STREAMS:
        raise ValueError(f"stream must be one of {sorted(STREAMS)}, got {stream!r}")
    if not isinstance(block, (int, np.integer)) or block < 0:
        raise ValueError(f"block must be a non-negative integer, got {block!r}")
    s_field, s_noise = STREAMS[stream]
    return (
        spawn_key("handover", s_field, int(block)),
        spawn_key("handover", s_noise, stable_id(float(speed_kmh)), int(block)),
    )


def draw_block(
    seed: int, speed_kmh: float, block: int, n_runs: int, kin: Kinematics, n_nodes: int, stream: str = "sweep"
) -> Draws:
    """The draws of block ``block`` (``n_runs`` crossings) at ``speed_kmh``.

    Parameters
    ----------
    seed : int
        Root seed of the study's random numbers.
    speed_kmh : float
        Train speed [km/h]; keys the measurement and GNSS noise (not the shadowing field).
    block : int
        Block index, ≥ 0.
    n_runs : int
        Train crossings in the block B, ≥ 1.
    kin : Kinematics
        Kinematics of the crossing at this speed (number of samples K, shadowing grid size G).
    n_nodes : int
        Relay-AP nodes N of the train.
    stream : str, optional
        ``sweep`` (evaluation runs, default) or ``cost`` (the separate cost-grid runs).

    Returns
    -------
    Draws
        float32 standard normals [1]: ``field_white`` [B, 2, G], ``meas_white``
        [B, N, 2, K] and ``gnss_white`` [B, K].

    Raises
    ------
    ValueError
        If ``n_runs`` < 1, ``block`` is not a non-negative integer or ``stream`` is unknown.
    """
    if n_runs < 1:
        raise ValueError(f"n_runs must be >= 1, got {n_runs!r}")
    key_field, key_noise = block_keys(speed_kmh, block, stream)
    rf = make_rng(seed, key_field)
    rn = make_rng(seed, key_noise)
    # float32 normals: twice as fast to draw; errors in dB need no more precision
    field_white = rf.standard_normal((n_runs, 2, kin.grid.n), dtype=np.float32)
    meas_white = rn.standard_normal((n_runs, n_nodes, 2, kin.n_samples), dtype=np.float32)
    gnss_white = rn.standard_normal((n_runs, kin.n_samples), dtype=np.float32)
    return Draws(
        field_white,
        meas_white,
        gnss_white,
        (int(seed), (*key_noise, FADING_SUBSTREAM)),
        (int(seed), (*key_field, SFN_SUBSTREAM)),
    )


@dataclass
class BlockContext:
    """Everything the policies of one block read (built once, shared by all policies)."""

    scn: Scenario
    kin: Kinematics
    zeta_db: np.ndarray  # [B, 2, G] shadowing on the grid (positive = extra loss)
    meas_dbm: np.ndarray  # [B, N, 2, K] raw measurements M
    filt_dbm: np.ndarray  # [B, N, 2, K] L3-filtered F
    gnss_err_m: np.ndarray  # [B, K]
    l3_a: float
    draws: Draws | None = None  # the block's draws (the fast fading is drawn from them on demand)
    _cache: dict = field(default_factory=dict)

    @property
    def n_runs(self) -> int:
        return self.zeta_db.shape[0]

    @property
    def n_nodes(self) -> int:
        return self.meas_dbm.shape[1]

    @property
    def xhat_head_m(self) -> np.ndarray:
        """Estimated head position [m], [B, K]."""
        return self.kin.x_head_m[None, :] + self.gnss_err_m

    def true_rsrp_dbm(self, run: np.ndarray, x_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Local-mean received power of both links at positions x of runs ``run`` [dBm]."""
        p_s, p_t = mean_rsrp_dbm(x_m, self.scn.radio)
        i = self.kin.grid.index(x_m)
        return p_s - self.zeta_db[run, 0, i], p_t - self.zeta_db[run, 1, i]

    def first_passage(self, level_m: np.ndarray) -> np.ndarray:
        """First sample k at which the estimated head position reaches ``level_m``.

        level_m: [..., B] (any leading axes); returns int [..., B], K − 1 if never.  The
        first k with x̂[k] ≥ level is the first with cummax(x̂)[k] ≥ level: one binary search
        per query on the row-offset, flattened running maximum.
        """
        if "flat" not in self._cache:
            cm = np.maximum.accumulate(self.xhat_head_m, axis=1)
            off = 2.0 * float(np.max(np.abs(cm))) + 1e4
            rows = np.arange(self.n_runs)
            self._cache["flat"] = (cm + off * rows[:, None]).ravel()
            self._cache["off"] = off
        flat, off = self._cache["flat"], self._cache["off"]
        k_n = self.kin.n_samples
        rows = np.arange(self.n_runs)
        level = np.asarray(level_m, dtype=float)
        off_level = np.clip(level, -off / 4, off / 4) + off * rows
        idx = np.searchsorted(flat, off_level, side="left") - rows * k_n
        return np.clip(idx, 0, k_n - 1)


def build_context(scn: Scenario, kin: Kinematics, draws: Draws, zeta_db: np.ndarray | None = None) -> BlockContext:
    """Shadowing, measurements, L3 filter and the position input of one block.

    Parameters
    ----------
    scn : Scenario
        The scenario (radio links, measurement noise, L3 filter, GNSS/INS error).
    kin : Kinematics
        Sample times and true node positions of the crossing (from
        :func:`railradio.handover.train.kinematics`).
    draws : Draws
        Standard normals of the block (from :func:`draw_block` with the same ``kin``).
    zeta_db : numpy.ndarray, optional
        A shadowing field [dB] [B, 2, G] on ``kin.grid`` to use instead of the one drawn (a
        hand-made field for tests; positive = extra loss). It is the nearest RRH's: with
        ``radio.sfn_rrhs`` > 1 the cells' other RRHs keep their drawn fields.

    Returns
    -------
    BlockContext
        ``zeta_db`` shadowing [dB] [B, 2, G] (with ``radio.sfn_rrhs`` > 1 the single-frequency
        cell's, :func:`railradio.handover.radio.sfn_shadowing`); ``meas_dbm`` raw RSRP measurements [dBm] and
        ``filt_dbm`` L3-filtered RSRP [dBm], both [B, N, 2, K] (link 0 serving, 1 target);
        ``gnss_err_m`` along-track position error [m] [B, K]; ``l3_a`` the L3 filter
        coefficient a [1] at the measurement period.

    Raises
    ------
    ValueError
        If ``draws.meas_white`` is not [B, N, 2, K] for the scenario's N and ``kin``'s K.
    """
    rd = scn.radio
    n_nodes = scn.train.n_nodes
    if draws.meas_white.shape[1:] != (n_nodes, 2, kin.n_samples):
        raise ValueError(
            f"draws do not match the scenario: meas_white {draws.meas_white.shape}, "
            f"expected [B, {n_nodes}, 2, {kin.n_samples}]"
        )
    if zeta_db is None:
        zeta = shadowing_fields(draws.field_white, kin.grid, rd)  # [B, 2, G]
    else:
        zeta = np.asarray(zeta_db, dtype=float)
        if zeta.shape != (draws.n_runs, 2, kin.grid.n):
            raise ValueError(f"zeta_db must be [B, 2, G] = [{draws.n_runs}, 2, {kin.grid.n}], got {zeta.shape}")
    if rd.sfn_rrhs > 1:  # each cell a single-frequency network: the power sum of its RRHs
        rho = ar1_coefficient(kin.grid.step_m, rd.shadow_corr_m)
        other = ar1_process(draws.sfn_white(rd.sfn_rrhs - 1), rho, rd.shadow_sigma_db)
        zeta = sfn_shadowing(zeta, other, kin.grid, rd)
    idx = kin.grid.index(kin.x_nodes_m)  # [N, K]
    p_s, p_t = mean_rsrp_dbm(kin.x_nodes_m, rd)  # [N, K]
    mean = np.stack([p_s, p_t], axis=1)  # [N, 2, K]
    # M = P_tx - L(d) - zeta + eps (eq. 1-2), built in place: [B, N, 2, K]
    meas = np.ascontiguousarray(zeta[:, :, idx].transpose(0, 2, 1, 3))
    np.subtract(mean[None], meas, out=meas)
    meas += rd.meas_sigma_db * draws.meas_white.astype(float)
    a = l3_coefficient_at(rd.l3_k, rd.meas_period_s, rd.l3_reference_period_s)
    filt = l3_filter(meas, a)
    return BlockContext(scn, kin, zeta, meas, filt, gnss_error_m(draws.gnss_white, scn), a, draws)


# --- execution (reconstruction eq. 3 and 8) --------------------------------------------


@dataclass
class Execution:
    """Outcome of executing the handover commands of a set of node crossings."""

    attempts: np.ndarray  # int, attempts made
    success: np.ndarray  # bool
    completion_x_m: np.ndarray  # He of the successful (or last) attempt [m]
    delay_s: np.ndarray  # command to completion, NaN if failed
    gap_db: np.ndarray  # true RSRP_s − RSRP_t at completion_x_m [dB]
    delay_all_s: np.ndarray  # command (or earlier RLF) to completion incl. re-establishment [s]
    t_detect_s: np.ndarray  # failure detection after the first command [s] (NaN: success)
    kind: np.ndarray | None = None  # stages rule: outcome class (railradio.handover.stages codes)
    stage: np.ndarray | None = None  # stages rule: the stage that failed (STAGE_* codes)
    occasions: np.ndarray | None = None  # stages rule: PRACH occasions used
    t310_at_command: np.ndarray | None = None  # stages rule: the serving link's T310 ran at the command


def rlf_window_samples(ex, period_s: float) -> tuple[int, int]:
    """(samples per out-of-sync evaluation, evaluations ending within T310 after the first)
    of the ``rlf`` failure rule on the T_m grid: round(rlf_eval_s/T_m) ≥ 1 and
    round(rlf_t310_s/T_m)."""
    return max(1, int(round(ex.rlf_eval_s / period_s))), int(round(ex.rlf_t310_s / period_s))


def rlm_positions_m(kin: Kinematics, indication_s: float) -> np.ndarray:
    """Positions [m] of the ``rlm`` rule's indications: every v·``indication_s`` from the
    start of the shadowing grid (behind the rearmost node at t = 0, where the serving link
    is strong) to its end."""
    g = kin.grid
    step = kin.speed_m_s * indication_s
    x_end = g.x_min_m + g.step_m * (g.n - 1)
    return g.x_min_m + step * np.arange(int(math.floor((x_end - g.x_min_m) / step)) + 1)


def rlm_failure_x_m(ctx: BlockContext) -> np.ndarray:
    """Where each run's serving link declares radio-link failure [m], [B] (inf: never):
    :mod:`railradio.handover.rlm` on the serving SINR along the track (cached per block)."""
    sc = ctx.scn
    cfg = sc.execution.rlm(sc.radio)
    key = ("rlm_x", cfg)
    if key not in ctx._cache:
        x = rlm_positions_m(ctx.kin, cfg.indication_s)
        r_s, r_t = ctx.true_rsrp_dbm(np.arange(ctx.n_runs)[:, None], x[None, :])
        oos, ins = indications(sinr_db(r_s, r_t, sc.radio), cfg)
        j = first_rlf(oos, ins, cfg)
        ctx._cache[key] = np.where(j < x.size, x[np.minimum(j, x.size - 1)], np.inf)
    return ctx._cache[key]


def serving_ok(ctx: BlockContext, run: np.ndarray, hb_m: np.ndarray) -> np.ndarray:
    """bool: the serving link has not failed at a command at true position ``hb_m``.

    ``instant`` (docs/model/handover.md §5): SINR_serving(H_b) ≥ Q_out.  ``rlf``: radio-link failure only
    after a T310-long run of out-of-sync evaluations — the link has failed iff every
    n_eval-sample mean (dB) of the serving SINR at the positions H_b − j·v·T_m, whose windows
    end at j = 0…n_t310, is below Q_out.  ``rlm``: radio-link monitoring (TS 36.133 §7.6,
    TS 36.331 §5.3.11) has declared failure before H_b (:func:`rlm_failure_x_m`).
    """
    sc = ctx.scn
    rd, ex = sc.radio, sc.execution
    if ex.failure_rule == "instant":
        r_s, r_t = ctx.true_rsrp_dbm(run, hb_m)
        return sinr_db(r_s, r_t, rd) >= rd.q_out_db
    if ex.failure_rule == "rlm":
        return np.asarray(hb_m, dtype=float) < rlm_failure_x_m(ctx)[run]
    n_eval, n_t = rlf_window_samples(ex, ctx.kin.period_s)
    step = ctx.kin.speed_m_s * ctx.kin.period_s
    x = hb_m[:, None] - step * np.arange(n_eval + n_t)[None, :]  # [n, J], j = 0 at H_b
    r_s, r_t = ctx.true_rsrp_dbm(run[:, None], x)
    s = sinr_db(r_s, r_t, rd)
    c = np.concatenate([np.zeros((s.shape[0], 1)), np.cumsum(s, axis=1)], axis=1)
    avg = (c[:, n_eval:] - c[:, :-n_eval]) / n_eval  # window ending at j = 0…n_t
    return np.any(avg >= rd.q_out_db, axis=1)


def rlm_failure_time_s(ctx: BlockContext, run: np.ndarray, hb_m: np.ndarray) -> np.ndarray:
    """Time [s] from a command at true position ``hb_m`` to the serving link's radio-link
    failure (negative: declared before it; inf: never) under the ``rlm`` rule."""
    return (rlm_failure_x_m(ctx)[run] - np.asarray(hb_m, dtype=float)) / ctx.kin.speed_m_s


def execution_samples(ex, indication_s: float) -> int:
    """Indications during one execution (T0) under the ``rlm`` rule: round(T0/T_ind) ≥ 1."""
    return max(1, int(round(ex.t0_s / indication_s)))


def target_ok(ctx: BlockContext, run: np.ndarray, hb_m: np.ndarray) -> np.ndarray:
    """bool: access to the target succeeds for an execution commanded at ``hb_m``.

    ``rlm``: the mean (dB) of the target's SINR at the execution's indications
    H_b + j·v·T_ind, j = 1…n (n = round(T0/T_ind), the last at H_e), is at least Q_out
    (TR 36.839's T304 rule).  ``instant``/``rlf``: SINR_target(H_e) ≥ Q_in.
    """
    sc = ctx.scn
    rd, ex = sc.radio, sc.execution
    v = ctx.kin.speed_m_s
    hb = np.asarray(hb_m, dtype=float)
    if ex.failure_rule != "rlm":
        he = hb + v * ex.t0_s
        r_s, r_t = ctx.true_rsrp_dbm(run, he)
        return sinr_db(r_t, r_s, rd) >= rd.q_in_db
    t_ind = ex.rlm_indication_s
    n = execution_samples(ex, t_ind)
    x = hb[:, None] + v * t_ind * np.arange(1, n + 1)[None, :]
    r_s, r_t = ctx.true_rsrp_dbm(run[:, None], x)
    return np.mean(sinr_db(r_t, r_s, rd), axis=1) >= rd.q_out_db


def link_monitor(ctx: BlockContext):
    """Both links' radio-link monitoring on the block's indication grid
    (:class:`railradio.handover.stages.LinkMonitor`, cached per block)."""
    from railradio.handover.stages import LinkMonitor

    sc = ctx.scn
    cfg = sc.execution.rlm(sc.radio)
    key = ("monitor", cfg)
    if key not in ctx._cache:
        x = rlm_positions_m(ctx.kin, cfg.indication_s)
        ctx._cache[key] = LinkMonitor(x, ctx.true_rsrp_dbm, ctx.n_runs, sc.radio, cfg)
    return ctx._cache[key]


def access_fading_db(ctx: BlockContext, run: np.ndarray, node: np.ndarray, hb_m: np.ndarray):
    """Fast-fading power gains [dB] of the serving and target link at the PRACH occasions of
    handovers (``run``, ``node``) commanded at ``hb_m``: two arrays [n, occasions], or
    ``None`` when ``radio.fading`` is ``none`` (:mod:`railradio.handover.fading`; the LOS
    Doppler's angle taken at the command position)."""
    from railradio.handover.fading import doppler_hz, power_gains_db

    rd, ex = ctx.scn.radio, ctx.scn.execution
    if rd.fading == "none":
        return None
    st = ex.stage_times()
    key = ("fading", st.n_occasions)
    if key not in ctx._cache:
        if ctx.draws is None:
            raise ValueError("radio.fading needs the block's draws in the context (build_context)")
        ctx._cache[key] = ctx.draws.fading(st.n_occasions)
    white, phase0 = ctx._cache[key]
    hb = np.asarray(hb_m, dtype=float)
    cos = np.stack(
        [
            (rd.x_serving_m - hb) / np.hypot(rd.x_serving_m - hb, rd.offset_m),
            (rd.x_target_m - hb) / np.hypot(rd.x_target_m - hb, rd.offset_m),
        ],
        axis=1,
    )
    k_db = None if rd.fading == "rayleigh" else rd.fading_k_db
    f_d = doppler_hz(ctx.kin.speed_m_s, rd.carrier_hz)
    g = power_gains_db(white[run, node], phase0[run, node], k_db, f_d, st.ra_period_s, cos, st.rrc_processing_s)
    return g[:, 0], g[:, 1]


def execute_stages(ctx: BlockContext, run: np.ndarray, hb_m: np.ndarray, node: np.ndarray | None = None) -> Execution:
    """Handovers commanded at true positions ``hb_m`` under the ``stages`` rule
    (:func:`railradio.handover.stages.execute_stages`): one attempt; a failed handover is
    recovered by re-establishment ``reestablish_s`` after the failure is detected.
    ``delay_s`` is command to completion (successes), ``delay_all_s`` that or, for a failure,
    the time from the command (or the earlier radio-link failure) to re-establishment."""
    from railradio.handover.stages import execute_stages as stages

    ex = ctx.scn.execution
    v = ctx.kin.speed_m_s
    hb = np.asarray(hb_m, dtype=float)
    if node is None:  # the engine's layout: crossing-major, every node of every crossing
        if hb.size != ctx.n_runs * ctx.n_nodes:
            raise ValueError("node must be given unless the handovers are every node of every crossing")
        node = np.tile(np.arange(ctx.n_nodes), ctx.n_runs)
    fading = access_fading_db(ctx, np.asarray(run), np.asarray(node), hb)
    out = stages(link_monitor(ctx), ex.stage_times(), run, hb, v, fading)
    delay = np.where(out.success, (out.completion_x_m - hb) / v, np.nan)
    delay_all = np.where(out.success, delay, ex.reestablish_s + np.maximum(np.nan_to_num(out.t_detect_s), 0.0))
    he = np.where(np.isfinite(out.completion_x_m), out.completion_x_m, hb + v * ex.t0_s)
    r_s, r_t = ctx.true_rsrp_dbm(run, he)
    return Execution(
        np.ones(hb.size, dtype=np.int64),
        out.success,
        he,
        delay,
        r_s - r_t,
        delay_all,
        out.t_detect_s,
        out.kind,
        out.stage,
        out.occasions,
        out.t310_at_command,
    )


def execute(ctx: BlockContext, run: np.ndarray, hb_m: np.ndarray, retry_allowed, node=None) -> Execution:
    """Execute handovers commanded at true positions ``hb_m`` (flat arrays, one per crossing).

    Attempt a succeeds iff the serving link holds at Hb_a (:func:`serving_ok`) and access
    to the target succeeds (:func:`target_ok`), with He_a = Hb_a + v·T0 [source eq. 2]; a
    failed attempt is followed by another at Hb_{a+1} = He_a + v·TZ when
    ``retry_allowed(a, serving_ok, hb_next_m)`` (bool array) says so.  Delay of a success
    at attempt a: a·T0 + (a−1)·TZ.  A handover whose last attempt fails is recovered by
    re-establishment, ``reestablish_s`` after the failure is detected: the radio-link
    failure when the serving link had failed (``rlm``: when it was declared; the other rules:
    at the command), else the end of the failed execution.  ``delay_all_s`` is, for every
    handover, the time to completion (that recovery included) from the first command, or
    from the radio-link failure when that came first (the command then cannot be received).
    """
    sc = ctx.scn
    ex = sc.execution
    if ex.failure_rule == "stages":
        return execute_stages(ctx, run, hb_m, node)
    v = ctx.kin.speed_m_s
    n = hb_m.shape[0]
    attempts = np.zeros(n, dtype=np.int64)
    success = np.zeros(n, dtype=bool)
    he_final = np.full(n, np.nan)
    t_detect = np.full(n, np.nan)  # failure detection, s after the first command
    done = np.zeros(n, dtype=bool)
    hb0 = hb_m.astype(float)
    hb = hb0.copy()
    for a in range(1, ex.max_attempts + 1):
        act = ~done
        if not act.any():
            break
        he = hb + v * ex.t0_s
        s_ok = serving_ok(ctx, run, hb)
        t_ok = target_ok(ctx, run, hb)
        ok = act & s_ok & t_ok
        hb_next = he + v * ex.tz_s
        retry = act & ~ok & (a < ex.max_attempts) & retry_allowed(a, s_ok, hb_next)
        stop = act & (ok | ~retry)
        attempts[stop] = a
        success[ok] = True
        he_final[stop] = he[stop]
        fail = stop & ~ok
        if fail.any():
            if ex.failure_rule == "rlm":
                t_rlf = rlm_failure_time_s(ctx, run[fail], hb0[fail])
            else:
                t_rlf = (hb[fail] - hb0[fail]) / v
            t_exec = (he[fail] - hb0[fail]) / v
            t_detect[fail] = np.where(s_ok[fail], t_exec, t_rlf)
        done |= stop
        hb = np.where(retry, hb_next, hb)
    delay = np.where(success, attempts * ex.t0_s + (attempts - 1) * ex.tz_s, np.nan)
    delay_all = np.where(success, delay, ex.reestablish_s + np.maximum(t_detect, 0.0))
    r_s, r_t = ctx.true_rsrp_dbm(run, he_final)
    return Execution(attempts, success, he_final, delay, r_s - r_t, delay_all, t_detect)
