"""Handover policies: one base class, a registry, and the three policies of the study.

A policy decides, for every node crossing of a block, the sample of its first handover
command, whether a failed attempt may be retried, and whether the node returns to the
previous cell after a successful handover (ping-pong).  :func:`run_policy` executes the
commands with the shared execution model and collects the outcomes.  All work is on
arrays over runs (and nodes, and weight settings); the only Python loops are over the N
nodes (the joint decision is sequential by construction) and over attempts.

- ``joint``: the position-power joint decision (our reconstruction of source §2).
- ``a3``: the A3 event with hysteresis, time-to-trigger and L3 filter [3GPP TS 36.331].
- ``distance``: the nearest RRH by the estimated position, re-evaluated every sample.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from railradio.handover.a3 import a3_entering, first_true, held_for, ttt_samples
from railradio.handover.band import (
    band_edges_m,
    fit_from_sums,
    geometric_weights,
    log_ratio,
    position_correction_m,
    sigma0_and_gaph,
    wslr_predict,
)
from railradio.handover.model import BlockContext, execute
from railradio.handover.radio import l3_coefficient_at, l3_filter


@dataclass
class Command:
    """First handover command of every node crossing and the policy's retry rule."""

    k: np.ndarray  # [B, N] sample of the first command
    retry: object  # callable(a, serving_ok, hb_next_m, flat_sel) -> bool
    extras: dict = field(default_factory=dict)  # name -> (dims, array, units, long_name)
    k_trigger: np.ndarray | None = None  # [B, N] start of the period that led to the command (None: k)


class Policy(ABC):
    """A handover policy: first command, retry rule, return (ping-pong) rule."""

    name: str = ""
    label: str = ""

    @abstractmethod
    def command(self, ctx: BlockContext) -> Command:
        """The first command per node crossing."""

    @abstractmethod
    def returns(self, ctx: BlockContext, k_from: np.ndarray, t_complete_s: np.ndarray) -> np.ndarray:
        """bool [B, N]: the node is commanded back to the previous cell within the ping-pong
        window after completing at ``t_complete_s``; ``k_from`` = first sample after it."""

    def _standard_retry(self, ctx: BlockContext):
        max_a = ctx.scn.execution.max_attempts

        def retry(a, serving_ok, hb_next_m, sel):
            # every policy (execution.retry = common): retried after TZ while the serving
            # link holds
            return serving_ok & (a < max_a)

        return retry


POLICIES: dict[str, type[Policy]] = {}


def register(cls: type[Policy]) -> type[Policy]:
    """Class decorator: add a policy to the registry under ``cls.name``."""
    if not cls.name or cls.name in POLICIES:
        raise ValueError(f"policy name {cls.name!r} is empty or already registered")
    POLICIES[cls.name] = cls
    return cls


def make_policy(name: str) -> Policy:
    """The registered policy called ``name``.

    Parameters
    ----------
    name : str
        Policy name: ``joint``, ``a3`` or ``distance`` (any registered in :data:`POLICIES`).

    Returns
    -------
    Policy
        A new instance of the policy class.

    Raises
    ------
    ValueError
        If no policy of that name is registered.
    """
    if name not in POLICIES:
        raise ValueError(f"policy must be one of {sorted(POLICIES)}, got {name!r}")
    return POLICIES[name]()


def _window(ctx: BlockContext, k_from: np.ndarray, t_complete_s: np.ndarray):
    """Sample indices [B, N, W] from ``k_from`` covering the ping-pong window, their validity
    and whether they are within the window."""
    kin = ctx.kin
    w = int(math.ceil(ctx.scn.execution.pingpong_window_s / kin.period_s)) + 2
    idx_raw = k_from[..., None] + np.arange(w)
    valid = idx_raw <= kin.n_samples - 1
    idx = np.minimum(idx_raw, kin.n_samples - 1)
    in_window = valid & (kin.t_s[idx] - t_complete_s[..., None] <= ctx.scn.execution.pingpong_window_s)
    return idx, in_window


@register
class A3Policy(Policy):
    """A3 event on L3-filtered RSRP, hysteresis and TTT (TS 36.331 §5.5.4.4)."""

    name = "a3"
    label = "A3 event"
    section = "a3"  # the Scenario field holding this policy's A3 parameters
    one_way = False  # the new cell lists the previous one as a neighbour (returns possible)

    def params(self, ctx: BlockContext):
        return getattr(ctx.scn, self.section)

    def _filtered(self, ctx: BlockContext) -> np.ndarray:
        """The L3-filtered RSRP this event reads [B, N, 2, K]: the block's, or filtered with
        the event's own filterCoefficient."""
        k = self.params(ctx).l3_k
        rd = ctx.scn.radio
        if k is None or k == rd.l3_k:
            return ctx.filt_dbm
        key = ("l3", k)
        if key not in ctx._cache:
            a = l3_coefficient_at(k, rd.meas_period_s, rd.l3_reference_period_s)
            ctx._cache[key] = l3_filter(ctx.meas_dbm, a)
        return ctx._cache[key]

    def _entering(self, ctx: BlockContext, to_target: bool) -> np.ndarray:
        """A3 entering condition at every sample, toward the target (or back), [B, N, K]."""
        key = f"{self.section}_entering_{to_target}"
        if key not in ctx._cache:
            gkey = f"{self.section}_gap"
            if gkey not in ctx._cache:  # F_target - F_serving, contiguous
                f = self._filtered(ctx)
                ctx._cache[gkey] = f[:, :, 1, :] - f[:, :, 0, :]
            d = ctx._cache[gkey]
            a3 = self.params(ctx)
            # Mn - Mp as one operand: (Mn - Mp) - Hys > Off, the same inequality
            ctx._cache[key] = a3_entering(d if to_target else -d, 0.0, a3.hysteresis_db, a3.offset_db)
        return ctx._cache[key]

    def command(self, ctx: BlockContext) -> Command:
        n_ttt = ttt_samples(self.params(ctx).ttt_s, ctx.kin.period_s)
        k = first_true(held_for(self._entering(ctx, True), n_ttt), default=ctx.kin.n_samples - 1)
        # the trigger: the first of the n_ttt samples whose entering condition held (the
        # start of the time-to-trigger that produced the report)
        return Command(k, self._standard_retry(ctx), k_trigger=np.maximum(k - (n_ttt - 1), 0))

    def returns(self, ctx, k_from, t_complete_s):
        if self.one_way:  # the previous cell is not a neighbour of the new one
            return np.zeros(np.shape(k_from), dtype=bool)
        n_ttt = ttt_samples(self.params(ctx).ttt_s, ctx.kin.period_s)
        idx, in_window = _window(ctx, k_from, t_complete_s)
        cond = np.take_along_axis(self._entering(ctx, False), idx, axis=-1)
        # the TTT timer starts after completion: count only samples from k_from on
        return np.any(in_window & held_for(cond, n_ttt), axis=-1)


@register
class RailA3Policy(A3Policy):
    """A3 as railways tune it (``handover.a3_rail``, :data:`railradio.handover.params.RAIL_A3`):
    its own filter coefficient, a short TTT, a small hysteresis, an offset toward the next
    cell, and a one-way neighbour list (the new cell never lists the previous one, so A3
    cannot send the train back)."""

    name = "a3_rail"
    label = "A3, railway-tuned"
    section = "a3_rail"
    one_way = True


@register
class DistancePolicy(Policy):
    """Serving cell = the RRH nearest the estimated position, re-evaluated every sample."""

    name = "distance"
    label = "distance trigger"

    def command(self, ctx: BlockContext) -> Command:
        xc = ctx.scn.radio.overlap_centre_m
        offs = ctx.kin.node_offsets_m
        level = np.broadcast_to(xc + offs[:, None], (offs.size, ctx.n_runs))
        k = ctx.first_passage(level).T  # [B, N]
        return Command(k, self._standard_retry(ctx))

    def returns(self, ctx, k_from, t_complete_s):
        idx, in_window = _window(ctx, k_from, t_complete_s)
        xhat = np.take_along_axis(ctx.xhat_head_m[:, None, :], idx, axis=-1) - ctx.kin.node_offsets_m[None, :, None]
        return np.any(in_window & (xhat < ctx.scn.radio.overlap_centre_m), axis=-1)


# --- the joint decision -----------------------------------------------------------------


@dataclass
class Band:
    """The head's band estimate, frozen at its trigger (per run, [B])."""

    k_head: np.ndarray
    a_db: np.ndarray
    n_hat: np.ndarray
    pl_m: np.ndarray
    pr_m: np.ndarray
    xm_m: np.ndarray
    gaph_db: float


def joint_gaps(ctx: BlockContext) -> np.ndarray:
    """Measured gaps serving − target the joint policy uses, [B, N, K] [dB]."""
    key = "joint_gaps"
    if key not in ctx._cache:
        y = ctx.filt_dbm if ctx.scn.joint.measurements == "l3" else ctx.meas_dbm
        ctx._cache[key] = y[:, :, 0, :] - y[:, :, 1, :]
    return ctx._cache[key]


def joint_regressors(ctx: BlockContext) -> np.ndarray:
    """Regressor r = log10((x_t − x̂)/(x̂ − x_s)) of every node's estimated position, passed
    through the same L3 filter as the gaps when the policy uses filtered gaps, [B, N, K].

    The model gap is linear in r (Ĝ = â + 10 n̂ r), and the L3 filter is linear with
    F_1 = M_1, so filtering r exactly as the measurements are filtered gives
    F(G) = â + 10 n̂ F(r): a fit of filtered gaps against F(r) carries no filter delay.
    Fitting them against the current r instead lags by (1 − a)/a samples (0.27 s at
    k = 4, 40 ms) and biases â by the gap's slope times that lag.
    """
    key = "joint_regressors"
    if key not in ctx._cache:
        xhat = ctx.xhat_head_m[:, None, :] - ctx.kin.node_offsets_m[None, :, None]
        r = log_ratio(xhat, ctx.scn.radio)
        ctx._cache[key] = l3_filter(r, ctx.l3_a) if ctx.scn.joint.measurements == "l3" else r
    return ctx._cache[key]


def head_band(ctx: BlockContext) -> Band:
    """Band estimate of the head and its trigger (reconstruction eq. 5–8).

    At every sample in the preparation zone (|x̂ − Xc| ≤ zone) the head refits
    Ĝ(x) = â + 10 n̂ log10((x_t − x)/(x − x_s)) to all its gap measurements since entering
    the zone (running least squares; with L3-filtered gaps the regressor is filtered alike,
    :func:`joint_regressors`), recomputes the execution band [PL, PR] (the completion
    band shifted back by v·T0) and triggers at the first sample with x̂ ≥ Xm = (PL + PR)/2.
    """
    sc = ctx.scn
    rd, jt = sc.radio, sc.joint
    v = ctx.kin.speed_m_s
    _, gaph = sigma0_and_gaph(rd, jt)
    g = joint_gaps(ctx)[:, 0, :]  # [B, K]
    xhat = ctx.xhat_head_m
    zone = np.abs(xhat - rd.overlap_centre_m) <= sc.train.prep_zone_m
    r = np.where(zone, joint_regressors(ctx)[:, 0, :], 0.0)
    gz = np.where(zone, g, 0.0)
    s1 = np.cumsum(zone, axis=1, dtype=float)
    sr, srr = np.cumsum(r, axis=1), np.cumsum(r * r, axis=1)
    sg, srg = np.cumsum(gz, axis=1), np.cumsum(r * gz, axis=1)
    a_hat, n_hat = fit_from_sums(s1, sr, srr, sg, srg, jt, rd.pathloss_exponent)
    pl_e, pr_e = band_edges_m(gaph, a_hat, n_hat, rd)
    # the command comes report_delay_s after the decision and completes T0 later
    pl, pr = pl_e - v * sc.execution.lead_s, pr_e - v * sc.execution.lead_s
    xm = 0.5 * (pl + pr)
    trig = (s1 >= jt.min_fit_samples) & (xhat >= xm)
    k = first_true(trig, default=ctx.kin.n_samples - 1)
    rows = np.arange(ctx.n_runs)
    return Band(k, a_hat[rows, k], n_hat[rows, k], pl[rows, k], pr[rows, k], xm[rows, k], gaph)


def joint_nodes(ctx: BlockContext, band: Band, weights: np.ndarray, method: str) -> dict[str, np.ndarray]:
    """Sequential multi-node decision for one or several weight vectors (eq. 9–14).

    Parameters
    ----------
    weights
        [A, m] weight vectors α_1…α_m (A settings evaluated on the same runs).
    method
        ``regression`` or ``mean`` (WSLR reading).

    Returns
    -------
    dict with ``k`` (command sample), ``x_trig_m`` (corrected trigger X_i), ``dp_db``
    (measured gap at the trigger, ΔP_i), ``dev_db`` (deviation from the fitted model),
    ``pred_db`` (the deviation ĉ_i predicted for node i from its predecessors', 0 for the
    head), each [A, B, N]; ``conv_price`` C and ``fluct`` F(A), each [A, B].

    Node i (0-based) uses the deviations of its min(m, i) predecessors: ĉ_i by WSLR,
    X_i = Xm + Δx(ĉ_i), and triggers at the first sample with x̂_i ≥ X_i but not before
    node i−1 (whose deviation it needs).
    """
    sc = ctx.scn
    rd, jt = sc.radio, sc.joint
    v = ctx.kin.speed_m_s
    weights = np.atleast_2d(np.asarray(weights, dtype=float))
    n_a, m = weights.shape
    b_n, n_n = ctx.n_runs, ctx.n_nodes
    rows = np.arange(b_n)
    gaps = joint_gaps(ctx)
    reg = joint_regressors(ctx)
    offs = ctx.kin.node_offsets_m
    pr_retry = band.pr_m - v * (sc.execution.lead_s + sc.execution.tz_s)
    k = np.zeros((n_a, b_n, n_n), dtype=np.intp)
    x_trig = np.zeros((n_a, b_n, n_n))
    dp = np.zeros((n_a, b_n, n_n))
    dev = np.zeros((n_a, b_n, n_n))
    pred = np.zeros((n_a, b_n, n_n))
    w = weights[:, None, :]  # [A, 1, m]
    for i in range(n_n):
        if i == 0:
            x_i = np.broadcast_to(band.xm_m, (n_a, b_n))
            k_i = np.broadcast_to(band.k_head, (n_a, b_n))
        else:
            p = min(m, i)
            preds = dev[:, :, i - p : i][:, :, ::-1]  # nearest first
            c = wslr_predict(preds, w, method)  # [A, B]
            pred[:, :, i] = c
            dx = position_correction_m(
                c, band.xm_m, band.pl_m, pr_retry, band.gaph_db, band.a_db, band.n_hat, jt.dead_zone_db, rd
            )
            x_i = band.xm_m + dx
            k_i = np.maximum(ctx.first_passage(x_i + offs[i]), k[:, :, i - 1])
        k[:, :, i] = k_i
        x_trig[:, :, i] = x_i
        dp_i = gaps[rows, i, k_i]  # [A, B]
        dp[:, :, i] = dp_i
        # deviation from the fitted model seen through the same filter (no filter lag)
        dev[:, :, i] = dp_i - (band.a_db + 10.0 * band.n_hat * reg[rows, i, k_i])
    converged = np.abs(dp) < jt.convergence_db
    conv_price = np.where(converged.any(axis=-1), np.argmax(converged, axis=-1) + 1, n_n + 1)
    width = np.maximum(band.pr_m - band.pl_m, 1e-9)
    fluct = np.minimum(1.0, x_trig.std(axis=-1) / width)
    return {
        "k": k,
        "x_trig_m": x_trig,
        "dp_db": dp,
        "dev_db": dev,
        "pred_db": pred,
        "conv_price": conv_price,
        "fluct": fluct,
    }


@register
class JointPolicy(Policy):
    """The position-power joint decision (our reconstruction of source §2)."""

    name = "joint"
    label = "joint decision"

    def command(self, ctx: BlockContext) -> Command:
        sc = ctx.scn
        jt = sc.joint
        if jt.m is None or jt.alpha is None:
            raise ValueError("joint.m and joint.alpha must be set (from the cost grid) before simulating")
        band = head_band(ctx)
        nodes = joint_nodes(ctx, band, geometric_weights(jt.m, jt.alpha)[None, :], jt.wslr)
        k = nodes["k"][0]
        v = ctx.kin.speed_m_s
        ex = sc.execution
        rows = np.arange(ctx.n_runs)
        xhat_cmd = (ctx.xhat_head_m[rows[:, None], k] - ctx.kin.node_offsets_m[None, :]).ravel()
        pr_flat = np.repeat(band.pr_m, ctx.n_nodes)
        back = v * ex.t0_s if jt.retry_rule == "completed" else 0.0

        def band_retry(a, serving_ok, hb_next_m, sel):
            # execution.retry = joint_band (the earlier joint-only rule, a case): one second
            # attempt, which must be executed (or completed) before PR (source eq. 9), judged
            # from the estimated position at the command plus v(T0 + TZ), serving link or not
            est = xhat_cmd[sel] + v * ex.report_delay_s + v * (ex.t0_s + ex.tz_s) * a + back
            return (a < 2) & (est <= pr_flat[sel])

        retry = band_retry if ex.retry == "joint_band" else self._standard_retry(ctx)

        extras = {
            "band_pl_m": (("run",), band.pl_m, "m", "execution band left edge PL (head's fit)"),
            "band_pr_m": (("run",), band.pr_m, "m", "execution band right edge PR"),
            "band_xm_m": (("run",), band.xm_m, "m", "band midpoint Xm (the head's trigger)"),
            "fit_offset_db": (("run",), band.a_db, "dB", "fitted gap offset a_hat"),
            "fit_exponent": (("run",), band.n_hat, "1", "fitted path-loss exponent n_hat"),
            "trigger_gap_db": (
                ("run", "node"),
                nodes["dp_db"][0],
                "dB",
                "measured gap serving - target at the trigger (Delta P_i)",
            ),
            "conv_price": (
                ("run",),
                nodes["conv_price"][0],
                "1",
                "convergence price C: first node with |Delta P| < threshold (N+1: none)",
            ),
            "fluct": (("run",), nodes["fluct"][0], "1", "fluctuation level F: std of X_i / (PR - PL)"),
        }
        return Command(k, retry, extras)

    def returns(self, ctx, k_from, t_complete_s):
        # unidirectional rule: once handed to cell j+1, cell j is never a target
        return np.zeros(k_from.shape, dtype=bool)


def _stage_outputs(ex, sh) -> dict[str, tuple]:
    """The ``stages`` rule's per-handover outputs (outcome class, failed stage, PRACH
    occasions, T310 at the command), shaped [B, N] by ``sh``."""
    from railradio.handover.stages import KIND_NAMES

    return {
        "failure_kind": (
            ("run", "node"),
            sh(ex.kind),
            "1",
            "outcome: " + ", ".join(f"{c} {n}" for c, n in KIND_NAMES.items()) + " (TS 36.300 22.4.2.2)",
        ),
        "failure_stage": (
            ("run", "node"),
            sh(ex.stage),
            "1",
            "failed stage: 0 none, 1 command reception, 2 access under T304, 3 the new link",
        ),
        "ra_occasions": (("run", "node"), sh(ex.occasions).astype(np.int16), "1", "PRACH occasions used"),
        "t310_at_command": (
            ("run", "node"),
            sh(ex.t310_at_command).astype(np.int8),
            "1",
            "1 if the serving link's T310 ran when the command came",
        ),
    }


def run_policy(policy: Policy, ctx: BlockContext) -> dict[str, tuple]:
    """Command, execute and check ping-pong for every node crossing of the block.

    Returns name -> (dims, array, units, long_name), dims over ("run", "node").

    Parameters
    ----------
    policy : Policy
        The policy (e.g. from :func:`make_policy`).
    ctx : BlockContext
        The block's radio and position arrays (from
        :func:`railradio.handover.model.build_context`).

    Returns
    -------
    dict of str to tuple
        name -> (dims, array, units, long_name), arrays [B, N] over ("run", "node"):
        ``command_x_m``, ``completion_x_m`` [m]; ``command_time_s``, ``delay_s`` (NaN: failed),
        ``delay_all_s``, ``delay_trigger_s`` [s]; ``attempts``, ``success``, ``pingpong`` [1]
        (int8); ``rsrp_gap_db`` [dB]; plus the policy's extras (the joint policy: band edges
        and midpoint [m] and fit over ("run",), ``trigger_gap_db`` [dB] over ("run", "node"),
        ``conv_price`` and ``fluct`` [1] over ("run",)).

    Raises
    ------
    ValueError
        For the joint policy, if ``joint.m`` or ``joint.alpha`` is not set.
    """
    cmd = policy.command(ctx)
    kin = ctx.kin
    b_n, n_n = ctx.n_runs, ctx.n_nodes
    run = np.repeat(np.arange(b_n), n_n)
    node = np.tile(np.arange(n_n), b_n)
    k = cmd.k.ravel()
    # the decision (a measurement report) at sample k; the command reaches the node
    # report_delay_s later
    t_cmd = kin.t_s[k] + ctx.scn.execution.report_delay_s
    hb = kin.speed_m_s * t_cmd - kin.node_offsets_m[node]

    def retry(a, serving_ok, hb_next_m):
        return cmd.retry(a, serving_ok, hb_next_m, slice(None))

    ex = execute(ctx, run, hb, retry, node)
    k_trig = (cmd.k if cmd.k_trigger is None else cmd.k_trigger).ravel()
    # trigger to completion, from the radio-link failure when that came before the trigger
    lead = t_cmd - kin.t_s[k_trig]
    delay_trigger = np.where(
        ex.success, lead + ex.delay_all_s, ctx.scn.execution.reestablish_s + np.maximum(ex.t_detect_s + lead, 0.0)
    )
    t_complete = t_cmd + np.nan_to_num(ex.delay_s)
    k_from = np.ceil(t_complete / kin.period_s - 1e-9).astype(np.intp)
    pp = policy.returns(ctx, k_from.reshape(b_n, n_n), t_complete.reshape(b_n, n_n)).ravel() & ex.success

    def sh(a):
        return a.reshape(b_n, n_n)

    out = {
        "command_x_m": (("run", "node"), sh(hb), "m", "true position of the first handover command Hb"),
        "command_time_s": (("run", "node"), sh(t_cmd), "s", "time of the first command since the head left x_s"),
        "completion_x_m": (
            ("run", "node"),
            sh(ex.completion_x_m),
            "m",
            "true completion position He of the successful (or last) attempt",
        ),
        "attempts": (("run", "node"), sh(ex.attempts).astype(np.int8), "1", "execution attempts"),
        "success": (("run", "node"), sh(ex.success).astype(np.int8), "1", "1 if the handover succeeded"),
        "delay_s": (("run", "node"), sh(ex.delay_s), "s", "first command to completion incl. retries (NaN: failed)"),
        "delay_all_s": (
            ("run", "node"),
            sh(ex.delay_all_s),
            "s",
            "first command, or an earlier radio-link failure, to completion, a failed "
            "handover's re-establishment included",
        ),
        "delay_trigger_s": (
            ("run", "node"),
            sh(delay_trigger),
            "s",
            "trigger (A3: start of the time-to-trigger; else the command), or an earlier "
            "radio-link failure, to completion, all handovers",
        ),
        "pingpong": (
            ("run", "node"),
            sh(pp).astype(np.int8),
            "1",
            "1 if commanded back to the previous cell within the ping-pong window",
        ),
        "rsrp_gap_db": (("run", "node"), sh(ex.gap_db), "dB", "true RSRP-GAP serving - target at completion"),
    }
    if ex.kind is not None:  # the stages rule
        out.update(_stage_outputs(ex, sh))
    out.update(cmd.extras)
    return out
