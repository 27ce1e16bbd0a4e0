"""Radio-link monitoring (TS 36.133 §7.6, TS 36.331 §5.3.11): indications, the
N310/N311/T310 procedure against a step-by-step reading of it, and the ``rlm`` failure rule
of the handover execution."""

from dataclasses import replace

import numpy as np
import pytest

from railradio.handover.model import build_context, draw_block, rlm_failure_x_m, rlm_positions_m, serving_ok
from railradio.handover.params import Execution, Scenario
from railradio.handover.rlm import RlmConfig, first_rlf, first_rlf_reference, indications
from railradio.handover.train import kinematics


def test_defaults_are_the_3gpp_values():
    cfg = Scenario().execution.rlm(Scenario().radio)
    assert (cfg.indication_s, cfg.qout_eval_s, cfg.qin_eval_s) == (0.010, 0.200, 0.100)
    assert (cfg.n310, cfg.n311, cfg.t310_s, cfg.q_out_db, cfg.q_in_db) == (1, 1, 1.0, -8.0, -6.0)
    assert cfg.t310_indications == 100 and cfg.samples(cfg.qout_eval_s) == 20


@pytest.mark.parametrize(("n310", "n311", "t310_s"), [(1, 1, 1.0), (3, 2, 0.2), (1, 5, 0.05), (6, 1, 0.0)])
def test_first_rlf_equals_the_procedure_step_by_step(n310, n311, t310_s):
    cfg = RlmConfig(n310=n310, n311=n311, t310_s=t310_s)
    rng = np.random.default_rng(5)
    # runs of out-of-sync and in-sync of random lengths, so that every branch is taken
    rows = []
    for _ in range(300):
        state = rng.integers(0, 3, size=rng.integers(1, 40))
        seq = np.repeat(state, rng.integers(1, 60, size=state.size))[:400]
        rows.append(np.pad(seq, (0, 400 - seq.size), constant_values=2))
    seqs = np.array(rows)
    oos, ins = seqs == 0, seqs == 1
    got = first_rlf(oos, ins, cfg)
    want = [first_rlf_reference(o, i, cfg) for o, i in zip(oos, ins, strict=True)]
    np.testing.assert_array_equal(got, want)
    assert 0 < np.mean(got < 400) < 1  # some rows fail, some do not


def test_t310_runs_from_n310_out_of_sync_and_stops_on_n311_in_sync():
    cfg = RlmConfig(n310=2, n311=2, t310_s=0.05)  # 5 indications
    f, o = False, True
    oos = np.array([f, o, o, f, f, f, f, f, f, f])
    none = np.zeros(10, dtype=bool)
    # T310 starts at the second out-of-sync (index 2), expires 5 indications later
    assert first_rlf(oos, none, cfg) == 7
    ins = none.copy()
    ins[4] = True  # one in-sync: N311 = 2 not reached
    assert first_rlf(oos, ins, cfg) == 7
    ins[5] = True  # two consecutive: T310 stopped
    assert first_rlf(oos, ins, cfg) == 10
    assert first_rlf(np.array([o, f, o, f, o]), np.zeros(5, bool), cfg) == 5  # never two in a row


def test_indications_use_full_windows_and_out_of_sync_takes_precedence():
    cfg = RlmConfig(qout_eval_s=0.04, qin_eval_s=0.02)  # 4 and 2 indications
    s = np.array([0.0, 0.0, -20.0, -20.0, -20.0, -20.0, -5.0, -5.0, 0.0, 0.0])
    oos, ins = indications(s, cfg)
    # 4-sample means from index 3: -10, -15, -20, -16.25, -12.5, -7.5, -2.5 (below -8 at 3..7)
    np.testing.assert_array_equal(oos, [False, False, False, True, True, True, True, True, False, False])
    # 2-sample means from index 1: 0, -10, -20, -20, -20, -12.5, -5, -2.5, 0: above -6 at 1, 7,
    # 8, 9, but index 7 is out-of-sync (precedence)
    np.testing.assert_array_equal(ins, [False, True, False, False, False, False, False, False, True, True])


@pytest.mark.parametrize(
    ("kw", "name"),
    [
        ({"n310": 0}, "n310"),
        ({"n311": 21}, "n311"),
        ({"t310_s": -1}, "t310_s"),
        ({"indication_s": 0}, "indication_s"),
        ({"q_in_db": -9}, "q_in_db"),
    ],
)
def test_bad_constants_raise_naming_the_parameter(kw, name):
    with pytest.raises(ValueError, match=name):
        RlmConfig(**kw)


def test_execution_rejects_bad_rlm_constants():
    with pytest.raises(ValueError, match="rlm_n310"):
        Execution(rlm_n310=0)
    with pytest.raises(ValueError, match="failure_rule"):
        Execution(failure_rule="t310")


def _quiet_rlm(**execution) -> Scenario:
    base = Scenario()
    radio = replace(base.radio, shadow_sigma_db=0.0, meas_sigma_db=0.0)
    return replace(base, radio=radio, execution=replace(base.execution, failure_rule="rlm", **execution))


def test_rlm_rule_fails_only_after_t310_of_out_of_sync():
    """Hand-made fields: the serving link 30 dB down over a stretch before H_b. It fails at
    H_b under ``rlm`` only if the stretch lasts the Qout window plus T310; ``instant`` fails
    on any stretch that covers H_b."""
    scn = _quiet_rlm()
    v_kmh = 360.0  # 100 m/s: an indication every 1 m
    kin = kinematics(scn, v_kmh)
    ctx = build_context(scn, kin, draw_block(1, v_kmh, 0, 3, kin, scn.train.n_nodes))
    hb = 700.0
    x = kin.grid.x_m
    # 200 ms window (20 m) + T310 (1 s, 100 m): ~112 m of the stretch before failure
    for run, length in enumerate((130.0, 80.0, -1.0)):
        ctx.zeta_db[run, 0, :] = np.where((x <= hb + 0.1) & (x >= hb - length), 30.0, 0.0)
        ctx.zeta_db[run, 1, :] = 0.0
    np.testing.assert_array_equal(serving_ok(ctx, np.arange(3), np.full(3, hb)), [False, True, True])
    x_rlf = rlm_failure_x_m(ctx)
    assert np.all(x_rlf[1:] > hb + 200.0)  # without a handover the link fails well past the midpoint
    # T310 starts once the 20-sample mean is below Q_out (fewer than 20 samples in), fails 100 later
    assert hb - 130.0 + 100.0 < x_rlf[0] < hb - 130.0 + 120.0, x_rlf[0]
    assert np.all(np.diff(rlm_positions_m(kin, 0.010)) == pytest.approx(1.0))
    ctx.scn = replace(scn, execution=replace(scn.execution, failure_rule="instant"))
    np.testing.assert_array_equal(serving_ok(ctx, np.arange(3), np.full(3, hb)), [False, False, True])
