"""The policies of the per-step reference loop (:mod:`railradio.handover.reference`): A3,
the railway-tuned A3, the distance trigger and the joint decision, one node and one sample
at a time, on a crossing computed by :class:`railradio.handover.reference._Run`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from railradio.handover.reference import _Run


def _outcome(run: _Run, i: int, k_cmd: int, retry_ok, returns, k_trig: int | None = None) -> dict:
    ex = run.scn.execution
    hb = run.x_true(i, k_cmd) + run.v * ex.report_delay_s  # the command, report_delay_s after the decision
    kind = None
    if ex.failure_rule == "stages":
        attempts, (ok, x_done, t_det, kind) = 1, run.execute_stages(hb, i)
        he = x_done if ok or not math.isnan(x_done) else hb + run.v * ex.t0_s
        delay = (x_done - hb) / run.v if ok else math.nan
        t_done_rel = delay if ok else t_det + ex.reestablish_s
        t_fail_stages = t_det
    else:
        attempts, ok, he, t_done_rel = run.execute(hb, retry_ok)
        delay = attempts * ex.t0_s + (attempts - 1) * ex.tz_s if ok else math.nan
    t_done = k_cmd * run.tm + ex.report_delay_s + (delay if ok else 0.0)
    pp = False
    if ok:
        k = math.ceil(t_done / run.tm - 1e-9)
        pp = returns(i, k, t_done)
    gap = run.true_rsrp(0, he) - run.true_rsrp(1, he)
    k_trig = k_cmd if k_trig is None else k_trig
    # the interruption starts at the first command or trigger, or at an earlier radio-link
    # failure (the completion minus the re-establishment time is the failure's detection)
    t_fail = t_fail_stages if kind is not None and not ok else t_done_rel - ex.reestablish_s
    lead = (k_cmd - k_trig) * run.tm + ex.report_delay_s
    start_all = 0.0 if ok else min(0.0, t_fail)
    start_trig = -lead if ok else min(-lead, t_fail)
    return {
        "k": k_cmd,
        "command_x_m": hb,
        "attempts": attempts,
        "success": ok,
        "delay_s": delay,
        "pingpong": pp,
        "completion_x_m": he,
        "rsrp_gap_db": gap,
        "delay_all_s": t_done_rel - start_all,
        "delay_trigger_s": t_done_rel - start_trig,
        **({"failure_kind": kind} if kind is not None else {}),
    }


def _a3(run: _Run, section: str = "a3", one_way: bool = False) -> list[dict]:
    sc = run.scn
    p = getattr(sc, section)
    hys, off = p.hysteresis_db, p.offset_db
    n_ttt = math.ceil(p.ttt_s / run.tm - 1e-9) + 1
    ex = sc.execution
    rd = sc.radio
    out = []
    for i in range(sc.train.n_nodes):
        f = run.filt[i]
        if p.l3_k is not None and p.l3_k != rd.l3_k:  # the event's own filter, sample by sample
            a = 1 - (1 - 1 / 2 ** (p.l3_k / 4)) ** (run.tm / rd.l3_reference_period_s)
            f = [[], []]
            for j in range(2):
                for k, mm in enumerate(run.meas[i][j]):
                    f[j].append(mm if k == 0 else (1 - a) * f[j][-1] + a * mm)
        count, k_cmd, k_trig = 0, run.k_n - 1, None
        for k in range(run.k_n):
            count = count + 1 if f[1][k] - hys > f[0][k] + off else 0  # A3-1, Mn = target
            if count == 1:
                k_trig = k  # the time-to-trigger starts
            if count >= n_ttt:
                k_cmd = k
                break
        if count < n_ttt:  # never reported: the command defaults to the last sample
            k_trig = max(k_cmd - (n_ttt - 1), 0)

        def returns(i, k0, t_done, f=f):
            """Ping-pong: the reverse A3 condition held for the TTT within the window after completion.

            Parameters
            ----------
            i, k0 : int
                Node index (unused: ``f`` is bound per node) and first sample after completion.
            t_done : float
                Completion time [s] from t = 0 (the head at the serving RRH).
            f : list of list of float
                The node's L3-filtered RSRP [dBm], indexed [link][k] (0 = serving, 1 = target).

            Returns
            -------
            bool
                True if the node is commanded back to the previous cell within ``pingpong_window_s``.
            """
            if one_way:  # the previous cell is not the new cell's neighbour
                return False
            count = 0
            for k in range(k0, run.k_n):
                if k * run.tm - t_done > ex.pingpong_window_s:
                    return False
                count = count + 1 if f[0][k] - hys > f[1][k] + off else 0  # back to the source
                if count >= n_ttt:
                    return True
            return False

        out.append(_outcome(run, i, k_cmd, lambda a, s_ok, hb: s_ok and a < ex.max_attempts, returns, k_trig))
    return out


def _distance(run: _Run) -> list[dict]:
    sc = run.scn
    xc = 0.5 * sc.radio.spacing_m
    ex = sc.execution
    out = []
    for i in range(sc.train.n_nodes):
        k_cmd = run.k_n - 1
        for k in range(run.k_n):
            if run.x_hat(i, k) >= xc:
                k_cmd = k
                break

        def returns(i, k0, t_done):
            for k in range(k0, run.k_n):
                if k * run.tm - t_done > ex.pingpong_window_s:
                    return False
                if run.x_hat(i, k) < xc:
                    return True
            return False

        out.append(_outcome(run, i, k_cmd, lambda a, s_ok, hb: s_ok and a < ex.max_attempts, returns))
    return out


def _joint(run: _Run) -> list[dict]:
    sc = run.scn
    rd, jt, ex = sc.radio, sc.joint, sc.execution
    L, v = rd.spacing_m, run.v
    a_l3 = 1 - (1 - 1 / 2 ** (rd.l3_k / 4)) ** (run.tm / rd.l3_reference_period_s)
    if jt.measurements == "raw":
        sigma0 = math.sqrt(2) * rd.meas_sigma_db
    else:
        sigma0 = math.sqrt(2) * rd.meas_sigma_db * math.sqrt(a_l3 / (2 - a_l3))
    gaph = (
        jt.gaph_gamma_db + jt.gaph_kappa * sigma0
        if jt.gaph_rule == "widen"
        else max(jt.gaph_gamma_db - jt.gaph_kappa * sigma0, jt.gaph_floor_db)
    )
    src = run.filt if jt.measurements == "l3" else run.meas

    def gap(i, k):
        """Measured gap serving − target of node ``i`` at sample ``k`` (``joint.measurements``).

        Parameters
        ----------
        i, k : int
            Node index (0 = head) and sample index.

        Returns
        -------
        float
            Gap [dB] of the L3-filtered (``l3``) or raw (``raw``) RSRP measurements.
        """
        return src[i][0][k] - src[i][1][k]

    def reg(x):
        x = min(max(x, 0.01), L - 0.01)
        return math.log10((L - x) / x)

    def band(a_hat, n_hat):
        q = 10 ** (gaph / (10 * n_hat))
        r = 10 ** (-a_hat / (10 * n_hat))
        pl_e, pr_e = L / (1 + q * r), L * q / (q + r)
        return pl_e - v * ex.lead_s, pr_e - v * ex.lead_s

    freg = _filtered_regressor(run, reg, a_l3)
    k_head, fit = _head_fit(run, freg, gap, band)
    ks = _node_commands(run, freg, gap, reg, k_head, fit, gaph)
    return _joint_outcomes(run, ks, fit[3])  # fit = (a_hat, n_hat, PL, PR, Xm)


def _filtered_regressor(run: _Run, reg, a_l3: float) -> list[list[float]]:
    """Regressor of every node's estimated position, L3-filtered like the gaps: [node][k]."""
    jt = run.scn.joint
    freg = []
    for i in range(run.scn.train.n_nodes):
        f_i = []
        for k in range(run.k_n):
            r = reg(run.x_hat(i, k))
            f_i.append(r if (k == 0 or jt.measurements == "raw") else (1 - a_l3) * f_i[-1] + a_l3 * r)
        freg.append(f_i)
    return freg


def _head_fit(run: _Run, freg: list[list[float]], gap, band) -> tuple[int, tuple]:
    """Head: running least squares in the zone, trigger at x_hat >= Xm.  Returns the head's
    command sample and the fit (a_hat, n_hat, PL, PR, Xm) there."""
    rd, jt, tr = run.scn.radio, run.scn.joint, run.scn.train
    xc = 0.5 * rd.spacing_m
    s1 = sr = srr = sg = srg = 0.0
    k_head, fit = run.k_n - 1, None
    for k in range(run.k_n):
        xh = run.x_hat(0, k)
        if abs(xh - xc) <= tr.prep_zone_m:
            r, g = freg[0][k], gap(0, k)
            s1 += 1
            sr += r
            srr += r * r
            sg += g
            srg += r * g
        if jt.band_fit == "offset":
            n_hat = rd.pathloss_exponent
        else:
            den = s1 * srr - sr * sr
            slope = (s1 * srg - sr * sg) / den if den > 1e-12 * max(s1 * srr, 1e-300) else 10 * rd.pathloss_exponent
            n_hat = min(max(slope / 10, jt.exponent_bounds[0]), jt.exponent_bounds[1])
        a_hat = (sg - 10 * n_hat * sr) / s1 if s1 > 0 else 0.0
        pl, pr = band(a_hat, n_hat)
        xm = 0.5 * (pl + pr)
        fit = (a_hat, n_hat, pl, pr, xm)
        if s1 >= jt.min_fit_samples and xh >= xm:
            k_head = k
            break
    return k_head, fit


def _node_commands(run: _Run, freg: list[list[float]], gap, reg, k_head: int, fit: tuple, gaph: float) -> list[int]:
    """Command sample of every node: the head's, then each follower's from the WSLR of the
    previous nodes' deviations from the head's fit."""
    jt, ex, tr = run.scn.joint, run.scn.execution, run.scn.train
    L, v = run.scn.radio.spacing_m, run.v
    a_hat, n_hat, pl, pr, xm = fit

    def model(x):
        return a_hat + 10 * n_hat * reg(x)

    def inv(g):
        return L / (1 + 10 ** ((g - a_hat) / (10 * n_hat)))

    pr_retry = pr - v * (ex.lead_s + ex.tz_s)
    w_all = [jt.alpha * (1 - jt.alpha) ** k for k in range(jt.m)]
    devs, ks, xs = [], [], []
    for i in range(tr.n_nodes):
        if i == 0:
            x_i, k_i = xm, k_head
        else:
            p = min(jt.m, i)
            d = [devs[i - 1 - k] for k in range(p)]
            w = [w_all[k] / sum(w_all[:p]) for k in range(p)]
            if jt.wslr == "mean" or p < 2:
                c = sum(wk * dk for wk, dk in zip(w, d, strict=True))
            else:
                pos = [float(i - 1 - k) for k in range(p)]
                slope, icpt = np.polyfit(pos, d, 1, w=np.sqrt(w))
                c = slope * i + icpt
            if abs(c) <= jt.dead_zone_db:
                x_i = xm
            elif c > gaph:
                x_i = pr_retry
            elif c < -gaph:
                x_i = pl
            else:
                x_i = inv(model(xm) - c)
            x_i = min(max(x_i, pl), max(pr_retry, pl))
            k_i = run.k_n - 1
            for k in range(run.k_n):
                if run.x_hat(i, k) >= x_i:
                    k_i = k
                    break
            k_i = max(k_i, ks[i - 1])
        ks.append(k_i)
        xs.append(x_i)
        devs.append(gap(i, k_i) - (a_hat + 10 * n_hat * freg[i][k_i]))
    return ks


def _joint_outcomes(run: _Run, ks: list[int], pr: float) -> list[dict]:
    """Outcomes of the nodes' commands at samples ``ks``; the joint retry rule uses the
    band's right edge ``pr``."""
    jt, ex, v = run.scn.joint, run.scn.execution, run.v
    out = []
    for i in range(run.scn.train.n_nodes):
        x_cmd_hat = run.x_hat(i, ks[i])
        back = v * ex.t0_s if jt.retry_rule == "completed" else 0.0

        def retry_ok(a, s_ok, hb, x_cmd_hat=x_cmd_hat, back=back):
            if ex.retry == "common":
                return s_ok and a < ex.max_attempts
            return a < 2 and x_cmd_hat + v * ex.report_delay_s + v * (ex.t0_s + ex.tz_s) * a + back <= pr

        out.append(_outcome(run, i, ks[i], retry_ok, lambda i, k0, t: False))
    return out


REFERENCE_POLICIES = {
    "joint": _joint,
    "a3": _a3,
    "a3_rail": lambda run: _a3(run, "a3_rail", one_way=True),
    "distance": _distance,
}
