"""A plain per-step loop implementation of the whole handover model.

Written independently of the vectorized engine (scalar ``math``, one run, one node, one
sample at a time, explicit state machines; WSLR by ``numpy.polyfit``), it consumes the
same :class:`~railradio.handover.model.Draws` and must give the same outcomes: the test
reference of :mod:`railradio.handover.policies` and the baseline of ``make bench``.
"""

from __future__ import annotations

import math

import numpy as np

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.handover.model import Draws
from railradio.handover.params import Scenario
from railradio.handover.reference_policies import REFERENCE_POLICIES
from railradio.handover.rlm import first_rlf_reference
from railradio.handover.train import Kinematics


class _Run:
    """One train crossing, computed sample by sample."""

    def __init__(self, scn: Scenario, kin: Kinematics, draws: Draws, b: int) -> None:
        self.scn, self.kin = scn, kin
        self.draws, self.b = draws, b
        rd, tr = scn.radio, scn.train
        self.v = kin.speed_m_s
        self.tm = rd.meas_period_s
        self.k_n = kin.n_samples
        g = kin.grid
        self.g_x0, self.g_dx, self.g_n = g.x_min_m, g.step_m, g.n
        # shadowing fields: AR(1) step by step
        rho = math.exp(-g.step_m / rd.shadow_corr_m)
        sig = rd.shadow_sigma_db
        innov = sig * math.sqrt(1.0 - rho * rho)

        def ar1(w) -> list[float]:
            z = [0.0] * g.n
            z[0] = sig * float(w[0])
            for n in range(1, g.n):
                z[n] = rho * z[n - 1] + innov * float(w[n])
            return z

        fields = [ar1(draws.field_white[b, j]) for j in range(2)]
        c = rd.shadow_cross_corr
        if c != 0.0:
            fields[1] = [c * a + math.sqrt(1 - c * c) * t for a, t in zip(fields[0], fields[1], strict=True)]
        self.zeta = fields
        # a single-frequency cell's other RRHs (radio.sfn_rrhs > 1): their own fields
        other = draws.sfn_white(rd.sfn_rrhs - 1)[b] if rd.sfn_rrhs > 1 else np.zeros((2, 0, g.n))
        self.zeta_other = [[ar1(other[j, k]) for k in range(other.shape[1])] for j in range(2)]
        # GNSS/INS error
        e = [0.0] * self.k_n
        if tr.gnss_sigma_m > 0:
            phi = math.exp(-self.tm / tr.gnss_corr_s)
            gi = tr.gnss_sigma_m * math.sqrt(1 - phi * phi)
            prev = tr.gnss_sigma_m * float(draws.gnss_white[b, 0])
            e[0] = prev
            for k in range(1, self.k_n):
                prev = phi * prev + gi * float(draws.gnss_white[b, k])
                e[k] = prev
            e = [min(max(x, -tr.gnss_bound_m), tr.gnss_bound_m) for x in e]
        self.err = e
        l0 = 20 * math.log10(4 * math.pi * rd.ref_distance_m * rd.carrier_hz / SPEED_OF_LIGHT_M_S)
        self.l0 = l0
        self.noise_mw = 10 ** ((-174 + 10 * math.log10(rd.bandwidth_hz) + rd.noise_figure_db) / 10)
        # measurements and L3 filter per node
        a = 1 - (1 - 1 / 2 ** (rd.l3_k / 4)) ** (self.tm / rd.l3_reference_period_s)
        self.meas, self.filt = [], []
        for i in range(tr.n_nodes):
            m_i, f_i = [[], []], [[], []]
            for k in range(self.k_n):
                x = self.x_true(i, k)
                for j in range(2):
                    mm = (
                        self.mean_rsrp(j, x) - self.field(j, x) + rd.meas_sigma_db * float(draws.meas_white[b, i, j, k])
                    )
                    m_i[j].append(mm)
                    f_i[j].append(mm if k == 0 else (1 - a) * f_i[j][-1] + a * mm)
            self.meas.append(m_i)
            self.filt.append(f_i)

    # --- geometry and radio -----------------------------------------------------------
    def x_true(self, i: int, k: int) -> float:
        """True position of node ``i`` at sample ``k``: the head's v·k·T_m minus i node spacings.

        Parameters
        ----------
        i, k : int
            Node index (0 = head) and sample index (time k·T_m).

        Returns
        -------
        float
            True along-track position [m] (serving RRH at 0, target at L_BS).
        """
        return self.v * (k * self.tm) - i * self.scn.train.node_spacing_m

    def x_hat(self, i: int, k: int) -> float:
        """Estimated position x̂ of node ``i`` at sample ``k``: true position plus GNSS/INS error.

        Parameters
        ----------
        i, k : int
            Node index (0 = head) and sample index (time k·T_m).

        Returns
        -------
        float
            Estimated along-track position [m] (the error is common to all nodes).
        """
        return self.v * (k * self.tm) + self.err[k] - i * self.scn.train.node_spacing_m

    def field(self, j: int, x: float) -> float:
        """Shadowing ζ of link ``j`` at ``x``: the value at the nearest grid point (clipped).

        Parameters
        ----------
        j : int
            Link, 0 = serving, 1 = target.
        x : float
            Along-track position [m].

        Returns
        -------
        float
            ζ [dB], positive = extra loss.
        """
        n = min(max(round((x - self.g_x0) / self.g_dx), 0), self.g_n - 1)
        z0 = self.zeta[j][n]
        if not self.zeta_other[j]:
            return z0
        # a single-frequency cell: the nearest RRH's mean minus this is the power sum of its RRHs
        xg = self.g_x0 + n * self.g_dx
        p0 = self.rrh_rsrp(j, 0, xg)
        total = sum(
            10 ** ((self.rrh_rsrp(j, k + 1, xg) - zk[n] - p0 + z0) / 10) for k, zk in enumerate(self.zeta_other[j])
        )
        return z0 - 10 * math.log10(1 + total)

    def mean_rsrp(self, j: int, x: float) -> float:
        """Mean received power P_tx − L(d) of link ``j``'s nearest RRH at ``x``, shadowing excluded.

        Parameters
        ----------
        j : int
            Link, 0 = serving, 1 = target.
        x : float
            Along-track position [m].

        Returns
        -------
        float
            Power [dBm]; d is the distance from x to the link's RRH, h off the track.
        """
        return self.rrh_rsrp(j, 0, x)

    def rrh_rsrp(self, j: int, k: int, x: float) -> float:
        """Mean received power P_tx − L(d) − A(φ) of RRH ``k`` of link ``j``'s cell at ``x``
        [dBm]: RRH 0 the nearest; the serving cell's others behind it, the target's ahead,
        one spacing apart (``radio.sfn_rrhs``)."""
        rd = self.scn.radio
        xj = -k * rd.spacing_m if j == 0 else (k + 1) * rd.spacing_m
        d = math.hypot(x - xj, rd.offset_m)
        pattern = 0.0
        if rd.antenna_hpbw_deg is not None:  # along the track, φ off boresight
            phi = math.degrees(math.atan2(rd.offset_m, abs(x - xj)))
            pattern = min(12 * (phi / rd.antenna_hpbw_deg) ** 2, rd.antenna_max_loss_db)
        return rd.tx_power_dbm - (self.l0 + 10 * rd.pathloss_exponent * math.log10(d / rd.ref_distance_m)) - pattern

    def true_rsrp(self, j: int, x: float) -> float:
        """Local-mean received power of link ``j`` at ``x``: the mean power minus the shadowing ζ.

        Parameters
        ----------
        j : int
            Link, 0 = serving, 1 = target.
        x : float
            True along-track position [m].

        Returns
        -------
        float
            Power [dBm], no measurement noise.
        """
        return self.mean_rsrp(j, x) - self.field(j, x)

    def sinr(self, wanted: int, x: float) -> float:
        """SINR of link ``wanted`` at ``x`` (true local means; the other link, times η, and noise interfere).

        Parameters
        ----------
        wanted : int
            Link whose SINR is computed, 0 = serving, 1 = target.
        x : float
            True along-track position [m].

        Returns
        -------
        float
            SINR [dB].
        """
        rd = self.scn.radio
        other = 1 - wanted
        i_mw = rd.load_factor * 10 ** (self.true_rsrp(other, x) / 10) + self.noise_mw
        return self.true_rsrp(wanted, x) - 10 * math.log10(i_mw)

    def serving_ok(self, hb: float) -> bool:
        """Serving link not failed at a command at hb (instant rule, or RLF after T310).

        Parameters
        ----------
        hb : float
            True position of the node at the command H_b [m].

        Returns
        -------
        bool
            True if the serving link holds by ``execution.failure_rule``.
        """
        ex, rd = self.scn.execution, self.scn.radio
        if ex.failure_rule == "instant":
            return self.sinr(0, hb) >= rd.q_out_db
        if ex.failure_rule == "rlm":
            return hb < self.rlm_failure_x()
        n_eval = max(1, round(ex.rlf_eval_s / self.tm))
        n_t = round(ex.rlf_t310_s / self.tm)
        step = self.v * self.tm
        sinrs = [self.sinr(0, hb - step * j) for j in range(n_eval + n_t)]
        for end in range(n_t + 1):  # out-of-sync windows ending j = end samples before hb
            if sum(sinrs[end : end + n_eval]) / n_eval >= rd.q_out_db:
                return True  # an in-sync evaluation within T310: no radio-link failure
        return False

    def rlm_failure_x(self) -> float:
        """Where radio-link monitoring declares the serving link failed (inf: never):
        indications every v·T_ind from the grid's start, window means by plain sums, the
        N310/N311/T310 procedure step by step."""
        if not hasattr(self, "_rlm_x"):
            cfg = self.scn.execution.rlm(self.scn.radio)
            xs, oos, ins = self._indications(0)
            j_rlf = first_rlf_reference(oos, ins, cfg)
            self._rlm_x = xs[j_rlf] if j_rlf < len(xs) else math.inf
        return self._rlm_x

    # --- execution ----------------------------------------------------------------------
    def target_ok(self, hb: float) -> bool:
        """Access to the target succeeds for an execution commanded at hb: rlm, the mean
        target SINR at the execution's indications (the last at He) >= Q_out; the other
        rules, the target SINR at He >= Q_in.

        Parameters
        ----------
        hb : float
            True position of the node at the command H_b [m]; H_e = H_b + v·T0.

        Returns
        -------
        bool
            True if access to the target succeeds.
        """
        ex, rd = self.scn.execution, self.scn.radio
        if ex.failure_rule != "rlm":
            return self.sinr(1, hb + self.v * ex.t0_s) >= rd.q_in_db
        n = max(1, round(ex.t0_s / ex.rlm_indication_s))
        vals = [self.sinr(1, hb + self.v * ex.rlm_indication_s * j) for j in range(1, n + 1)]
        return sum(vals) / n >= rd.q_out_db

    # --- the stages rule, step by step -------------------------------------------------
    def _indications(self, link: int) -> tuple[list[float], list[bool], list[bool]]:
        """Indication positions and the out-of-sync / in-sync indications of ``link`` (its
        SINR window means by plain sums)."""
        cfg = self.scn.execution.rlm(self.scn.radio)
        step = self.v * cfg.indication_s
        x_end = self.g_x0 + self.g_dx * (self.g_n - 1)
        xs = [self.g_x0 + step * j for j in range(int(math.floor((x_end - self.g_x0) / step)) + 1)]
        sinrs = [self.sinr(link, x) for x in xs]
        n_out, n_in = cfg.samples(cfg.qout_eval_s), cfg.samples(cfg.qin_eval_s)
        oos, ins = [], []
        for j in range(len(xs)):
            o = j + 1 >= n_out and sum(sinrs[j + 1 - n_out : j + 1]) / n_out < cfg.q_out_db
            i = j + 1 >= n_in and sum(sinrs[j + 1 - n_in : j + 1]) / n_in > cfg.q_in_db
            oos.append(o)
            ins.append(i and not o)
        return xs, oos, ins

    def fading_db(self, node: int, hb: float, n_occ: int) -> list[tuple[float, float]]:
        """Fast-fading power gains [dB] (serving, target) at the ``n_occ`` PRACH occasions of
        node ``node``'s handover commanded at ``hb``, occasion by occasion."""
        from railradio.handover.fading import clarke_factor

        rd, ex = self.scn.radio, self.scn.execution
        if rd.fading == "none":
            return [(0.0, 0.0)] * n_occ
        f_d = self.v * rd.carrier_hz / SPEED_OF_LIGHT_M_S
        if getattr(self, "_fade", (None,))[0] != n_occ:
            self._fade = (n_occ, *self.draws.fading(n_occ), clarke_factor(n_occ, f_d, ex.ra_period_s))
        _, white, phase0, lf = self._fade
        k = None if rd.fading == "rayleigh" else 10 ** (rd.fading_k_db / 10)
        out = [[0.0, 0.0] for _ in range(n_occ)]
        for j, x_rrh in enumerate((rd.x_serving_m, rd.x_target_m)):
            w = white[self.b, node, j]
            z = [complex(float(w[m, 0]), float(w[m, 1])) / math.sqrt(2) for m in range(n_occ)]
            cos = (x_rrh - hb) / math.hypot(x_rrh - hb, rd.offset_m)
            for o in range(n_occ):
                g = sum(float(lf[o, m]) * z[m] for m in range(o + 1))
                if k is not None:
                    t = ex.rrc_processing_s + ex.ra_period_s * o
                    phi = 2 * math.pi * (float(phase0[self.b, node, j]) + f_d * cos * t)
                    g = math.sqrt(k / (k + 1)) * complex(math.cos(phi), math.sin(phi)) + math.sqrt(1 / (k + 1)) * g
                out[o][j] = 10 * math.log10(max(abs(g) ** 2, 1e-30))
        return [tuple(o) for o in out]

    def execute_stages(self, hb: float, node: int = 0) -> tuple[bool, float, float, int]:
        """The stages rule for a command reaching the node at ``hb``: (success, completion
        position (NaN: none), failure detection after the command [s] (NaN: success),
        outcome class of :mod:`railradio.handover.stages`), each stage read as the
        procedure runs."""
        ex, rd = self.scn.execution, self.scn.radio
        cfg = ex.rlm(rd)
        if not hasattr(self, "_ind"):
            self._ind = (self._indications(0), self._indications(1))
        (xs, oos, ins), (_, oos_t, ins_t) = self._ind
        step = xs[1] - xs[0]
        # stage 2: T310 of the serving link, from the start of the crossing to the command
        start, c_o, c_i, t310, x_rlf = None, 0, 0, False, math.inf
        for j, x in enumerate(xs):
            if x > hb + 1e-9 * step:
                break
            if start is None:
                c_o = c_o + 1 if oos[j] else 0
                if c_o >= cfg.n310:
                    start, c_i = j, 0
            else:
                c_i = c_i + 1 if ins[j] else 0
                if c_i >= cfg.n311:
                    start, c_o = None, 0
            t310 = start is not None
            if start is not None and j - start >= cfg.t310_indications:
                x_rlf = x
                break
        if t310 or x_rlf <= hb:
            t_det = min((x_rlf - hb) / self.v, 0.0)
            return False, math.nan, t_det, self._kind(hb + self.v * t_det, late=True)
        # stage 3: PRACH occasions while T304 runs
        n_occ = int(math.floor((ex.t304_s - ex.rrc_processing_s) / ex.ra_period_s + 1e-9)) + 1
        fad = self.fading_db(node, hb, n_occ)
        for i in range(n_occ):
            t = ex.rrc_processing_s + ex.ra_period_s * i
            x = hb + self.v * t
            g_s, g_t = fad[i]
            i_mw = rd.load_factor * 10 ** ((self.true_rsrp(0, x) + g_s) / 10) + self.noise_mw
            if self.true_rsrp(1, x) + g_t - 10 * math.log10(i_mw) >= rd.q_out_db:
                x_done = hb + self.v * (t + ex.t0_s - ex.rrc_processing_s)
                break
        else:
            return False, math.nan, ex.t304_s, self._kind(hb + self.v * ex.t304_s, late=False)
        # stage 4: the new link afresh from completion
        j_done = math.ceil((x_done - xs[0]) / step - 1e-9)
        j_last = j_done + round(ex.monitor_s / cfg.indication_s)
        start, c_o, c_i = None, 0, 0
        for j in range(max(j_done + cfg.samples(cfg.qout_eval_s) - 1, 0), len(xs)):
            if start is None:
                if j > j_last:
                    break
                c_o = c_o + 1 if oos_t[j] else 0
                if c_o >= cfg.n310:
                    start, c_i = j, 0
            else:
                c_i = c_i + 1 if ins_t[j] else 0
                if c_i >= cfg.n311:
                    start, c_o = None, 0
            if start is not None and j - start >= cfg.t310_indications:
                return False, x_done, (xs[j] - hb) / self.v, self._kind(xs[j], late=False)
        return True, x_done, math.nan, 0

    def _kind(self, x_fail: float, late: bool) -> int:
        """Too late (1) / too early (2) / other (4) by the stronger cell at ``x_fail``."""
        to_target = self.true_rsrp(1, x_fail) > self.true_rsrp(0, x_fail)
        if late:
            return 1 if to_target else 4
        return 4 if to_target else 2

    def execute(self, hb: float, retry_ok) -> tuple[int, bool, float, float]:
        """(attempts, success, completion position, time of completion after the first
        command — a failure's detection plus re-establishment) from a first command at hb.

        Parameters
        ----------
        hb : float
            True position of the node at its first command H_b [m].
        retry_ok : callable
            ``retry_ok(a, s_ok, hb_next)`` -> bool, asked while a < ``max_attempts``: whether the
            failed attempt a (from 1; ``s_ok``: its serving link held) is retried at ``hb_next`` [m].

        Returns
        -------
        tuple of (int, bool, float, float)
            Attempts made; success; completion position H_e of the last attempt [m]; time [s]
            from the first command to completion, a·T0 + (a − 1)·TZ, or for a failure to its
            detection (negative: radio-link failure before the command) plus re-establishment.
        """
        ex = self.scn.execution
        hb0 = hb
        a = 1
        while True:
            he = hb + self.v * ex.t0_s
            s_ok = self.serving_ok(hb)
            if s_ok and self.target_ok(hb):
                return a, True, he, a * ex.t0_s + (a - 1) * ex.tz_s
            hb_next = he + self.v * ex.tz_s
            if a < ex.max_attempts and retry_ok(a, s_ok, hb_next):
                a += 1
                hb = hb_next
                continue
            if s_ok:
                t_fail = (he - hb0) / self.v
            elif ex.failure_rule == "rlm":
                t_fail = (self.rlm_failure_x() - hb0) / self.v
            else:
                t_fail = (hb - hb0) / self.v
            return a, False, he, t_fail + ex.reestablish_s


def simulate_reference(scn: Scenario, kin: Kinematics, draws: Draws, policies: tuple[str, ...]) -> dict:
    """Outcomes per policy as arrays [B, N] (keys as :func:`railradio.handover.policies.run_policy`).

    Parameters
    ----------
    scn : Scenario
        The scenario; the joint policy needs ``scn.joint.m`` and ``scn.joint.alpha`` set.
    kin : Kinematics
        Kinematics of the crossing at one speed.
    draws : Draws
        Standard normals of the block (the same the vectorized engine consumes).
    policies : tuple of str
        Policy names among ``joint``, ``a3`` and ``distance``.

    Returns
    -------
    dict of str to dict of str to numpy.ndarray
        Per policy, arrays [B, N]: ``k`` (first command sample), ``command_x_m``,
        ``completion_x_m`` [m], ``attempts`` [1], ``success`` and ``pingpong`` (bool),
        ``delay_s`` (NaN: failed), ``delay_all_s``, ``delay_trigger_s`` [s], ``rsrp_gap_db`` [dB].

    Raises
    ------
    KeyError
        If a policy name is not one of :data:`REFERENCE_POLICIES`.
    """
    res = {p: [] for p in policies}
    for b in range(draws.n_runs):
        run = _Run(scn, kin, draws, b)
        for p in policies:
            res[p].append(REFERENCE_POLICIES[p](run))
    out = {}
    for p in policies:
        out[p] = {key: np.array([[node[key] for node in r] for r in res[p]]) for key in res[p][0][0]}
    return out
