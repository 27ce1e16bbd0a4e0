"""The handover's failure stages (railradio.handover.stages): the compiled monitoring against
the procedure as written, and each stage failing where a hand-made field says it must."""

import numpy as np
import pytest

from railradio.handover.params import Radio
from railradio.handover.rlm import RlmConfig, first_rlf_reference, indications
from railradio.handover.stages import (
    OTHER_RLF,
    STAGE_ACCESS,
    STAGE_COMMAND,
    STAGE_NEW_LINK,
    STAGE_NONE,
    SUCCESS,
    TOO_EARLY,
    TOO_LATE,
    LinkMonitor,
    StageTimes,
    _rlf_after,
    _t310_running,
    execute_stages,
)

CFG = RlmConfig()
TIMES = StageTimes(report_delay_s=0.05, rrc_processing_s=0.015, t0_s=0.03, ra_period_s=0.01, t304_s=0.5, monitor_s=1.0)
V = 100.0  # m/s: indications 1 m apart


def _t310_reference(oos, ins, cfg):
    """T310 running after each indication, as TS 36.331 §5.3.11 reads (True from RLF on)."""
    running, start, c_oos, c_in = [], None, 0, 0
    for j, (o, i) in enumerate(zip(oos, ins, strict=True)):
        if start is None:
            c_oos = c_oos + 1 if o else 0
            if c_oos >= cfg.n310:
                start, c_in = j, 0
        else:
            c_in = c_in + 1 if i else 0
            if c_in >= cfg.n311:
                start, c_oos = None, 0
        running.append(start is not None)
        if start is not None and j - start >= cfg.t310_indications:
            return running + [True] * (len(oos) - j - 1)
    return running


@pytest.mark.parametrize("n310", [1, 3])
def test_t310_state_is_the_procedure(n310):
    cfg = RlmConfig(n310=n310, n311=2, t310_s=0.3)
    rng = np.random.default_rng(4)
    sinr = np.cumsum(rng.normal(0, 1.5, (40, 400)), axis=1) * 0.3 - 7.0  # wandering around Q_out
    oos, ins = indications(sinr, cfg)
    running, rlf = _t310_running(oos, ins, cfg.n310, cfg.n311, cfg.t310_indications)
    for r in range(sinr.shape[0]):
        assert list(running[r]) == _t310_reference(oos[r], ins[r], cfg)
        assert rlf[r] == first_rlf_reference(oos[r], ins[r], cfg)
    # afresh from an indication: the same as the procedure on the row's tail
    j0 = np.full(40, 150)
    got = _rlf_after(oos, ins, np.arange(40), j0, np.full(40, 10**6), cfg.n310, cfg.n311, cfg.t310_indications)
    for r in range(40):
        j = first_rlf_reference(oos[r, 150:], ins[r, 150:], cfg)
        assert got[r] == (150 + j if j < 250 else -1)


def _monitor(serving_db, target_db):
    """A block of one crossing whose links' SINRs are set by hand: piecewise-constant local
    means on a 1 m indication grid (noise far below, no load coupling)."""
    x = np.arange(0.0, 2000.0, 1.0)
    radio = Radio(load_factor=1e-9)

    def means(run, x_m):
        j = np.clip(np.floor(np.asarray(x_m, dtype=float)).astype(int), 0, x.size - 1)
        n_dbm = -97.0
        return n_dbm + serving_db(x)[j] + 0 * run, n_dbm + target_db(x)[j] + 0 * run

    return LinkMonitor(x, means, 1, radio, CFG)


def _one(mon, hb):
    return execute_stages(mon, TIMES, np.array([0]), np.array([float(hb)]), V)


def test_a_clean_handover_completes_at_t0():
    mon = _monitor(lambda x: np.full(x.shape, 20.0), lambda x: np.full(x.shape, 20.0))
    out = _one(mon, 1000)
    assert out.success[0] and out.kind[0] == SUCCESS and out.stage[0] == STAGE_NONE
    assert out.completion_x_m[0] == pytest.approx(1000 + V * 0.03)


def test_a_command_while_t310_runs_is_lost_and_too_late():
    """The serving link drops below Q_out 30 m (0.3 s) before the command: T310 runs then
    (started after the 200 ms window), so the command is lost; the target is stronger: too late."""
    mon = _monitor(lambda x: np.where(x < 970, 20.0, -15.0), lambda x: np.full(x.shape, 20.0))
    out = _one(mon, 1000)
    assert not out.success[0] and out.t310_at_command[0]
    assert out.stage[0] == STAGE_COMMAND and out.kind[0] == TOO_LATE and out.t_detect_s[0] == 0.0


def test_a_serving_failure_in_the_stronger_cell_is_not_a_mobility_failure():
    mon = _monitor(lambda x: np.where(x < 970, 20.0, -15.0), lambda x: np.full(x.shape, -30.0))
    assert _one(mon, 1000).kind[0] == OTHER_RLF


def test_access_waits_for_an_occasion_above_q_out_within_t304():
    # the target rises above Q_out 20 m (0.2 s) after the command: access at that occasion
    mon = _monitor(lambda x: np.full(x.shape, 20.0), lambda x: np.where(x < 1020, -15.0, 20.0))
    out = _one(mon, 1000)
    assert out.success[0] and out.occasions[0] == 20  # the 20th: 15 ms + 19 * 10 ms = 205 ms, at 1020.5 m
    # ... and never within T304: the handover fails there, too early (the source is stronger)
    mon = _monitor(lambda x: np.full(x.shape, 20.0), lambda x: np.where(x < 1200, -15.0, 20.0))
    out = _one(mon, 1000)
    assert not out.success[0] and out.stage[0] == STAGE_ACCESS and out.kind[0] == TOO_EARLY
    assert out.t_detect_s[0] == pytest.approx(TIMES.t304_s)


def test_the_new_link_failing_soon_after_completion_is_too_early():
    # access succeeds, then the target falls below Q_out 50 m (0.5 s) later for good
    tgt = lambda x: np.where((x >= 1050) & (x < 1900), -15.0, 20.0)  # noqa: E731
    mon = _monitor(lambda x: np.full(x.shape, 20.0), tgt)
    out = _one(mon, 1000)
    assert not out.success[0] and out.stage[0] == STAGE_NEW_LINK and out.kind[0] == TOO_EARLY
    # the same dip starting 1.5 s after completion is outside the monitoring: a success
    tgt = lambda x: np.where((x >= 1160) & (x < 1900), -15.0, 20.0)  # noqa: E731
    assert _one(_monitor(lambda x: np.full(x.shape, 20.0), tgt), 1000).success[0]


def test_stage_times_are_checked():
    with pytest.raises(ValueError, match="rrc_processing_s"):
        StageTimes(0.05, 0.04, 0.03, 0.01, 0.5, 1.0)
    with pytest.raises(ValueError, match="ra_period_s"):
        StageTimes(0.05, 0.015, 0.03, 0.0, 0.5, 1.0)
    assert TIMES.n_occasions == 49
