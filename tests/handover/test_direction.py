"""The failure model's direction (docs/model/handover.md §5): a late trigger fails, and a
time-triggered policy's too-late share does not fall with speed on the same fields."""

from dataclasses import replace

import numpy as np

from railradio.handover.model import build_context, draw_block
from railradio.handover.params import Scenario
from railradio.handover.policies import make_policy, run_policy
from railradio.handover.stages import SUCCESS, TOO_LATE
from railradio.handover.train import kinematics


def _run(scn, speed, zeta=None, n_runs=4, block=0, policies=("a3", "distance")):
    kin = kinematics(scn, speed)
    draws = draw_block(5, speed, block, n_runs, kin, scn.train.n_nodes)
    if zeta is not None:
        zeta = np.broadcast_to(zeta(kin.grid.x_m), (n_runs, 2, kin.grid.n)).copy()
    ctx = build_context(scn, kin, draws, zeta)
    return {p: run_policy(make_policy(p), ctx) for p in policies}


def test_a_serving_fade_before_the_a3_report_makes_a3_fail_too_late():
    """A hand-made field: no shadowing, then the serving link drops by 30 dB 150 m before the
    overlap centre (a cutting). A3 reports only after its filter and TTT see the drop, so its
    command comes while T310 runs (TR 36.839): too late, re-established in the target. The
    distance trigger, commanded at the centre later still, fails the same way; without the
    drop both succeed."""
    scn = replace(Scenario(), radio=replace(Scenario().radio, shadow_sigma_db=0.0, fading="none"))
    xc = scn.radio.overlap_centre_m

    def cutting(x):
        return np.stack([np.where(x > xc - 150.0, 30.0, 0.0), np.zeros_like(x)])

    clear = _run(scn, 350.0)
    faded = _run(scn, 350.0, cutting)
    for pol in ("a3", "distance"):
        assert np.all(clear[pol]["failure_kind"][1] == SUCCESS), pol
        assert np.all(faded[pol]["failure_kind"][1] == TOO_LATE), pol
        assert np.all(faded[pol]["t310_at_command"][1] > 0), pol


def test_a3_too_late_does_not_fall_with_speed():
    """The same shadowing fields at every speed (common random numbers): A3's trigger waits
    for its filter and time-to-trigger, a fixed time that covers more track at speed, so its
    too-late share may not fall from 100 to 500 km/h (each step allowed two standard errors of
    Monte Carlo noise)."""
    scn = Scenario().with_weights(3, 0.4)
    shares = []
    for v in (100.0, 250.0, 350.0, 500.0):
        kinds = np.concatenate(
            [_run(scn, v, n_runs=60, block=b, policies=("a3",))["a3"]["failure_kind"][1].ravel() for b in range(3)]
        )
        shares.append(np.mean(kinds == TOO_LATE))
    n = 3 * 60 * scn.train.n_nodes
    for lo, hi in zip(shares, shares[1:], strict=False):
        se = np.sqrt(max(lo * (1 - lo), 1.0 / n) / n)
        assert hi >= lo - 2 * se * np.sqrt(2), shares
    assert shares[-1] > shares[0], shares


def _timers_scaled(scn, factor):
    """Every time constant of the procedure and of the measurements times ``factor``."""
    ex, rd = scn.execution, scn.radio
    names = (
        "t0_s",
        "report_delay_s",
        "rrc_processing_s",
        "ra_period_s",
        "t304_s",
        "monitor_s",
        "rlf_t310_s",
        "rlf_eval_s",
        "rlm_indication_s",
        "rlm_qin_eval_s",
    )
    ex = replace(ex, **{n: getattr(ex, n) * factor for n in names})
    return replace(scn, execution=ex, radio=replace(rd, meas_period_s=rd.meas_period_s * factor))


def test_a_position_trigger_meets_the_same_procedure_when_its_timers_scale_with_speed():
    """Why a position trigger's too-late share falls with speed: the shadowing lies along the
    track, the procedure's timers run in time. With every time constant scaled by 1/v (and
    no GNSS error or fast fading), the distance trigger meets the same procedure at the same
    places: its outcomes at 100 km/h and 500 km/h agree, handover by handover, while with the
    standard's timers they differ."""
    base = replace(
        Scenario(), radio=replace(Scenario().radio, fading="none"), train=replace(Scenario().train, gnss_sigma_m=0.0)
    )
    slow = _run(_timers_scaled(base, 5.0), 100.0, n_runs=200, policies=("distance",))["distance"]
    fast = _run(base, 500.0, n_runs=200, policies=("distance",))["distance"]
    same = np.mean(slow["failure_kind"][1] == fast["failure_kind"][1])
    assert same > 0.995, same
    assert np.mean(fast["failure_kind"][1] == TOO_LATE) > 0  # not vacuous
    standard = _run(base, 100.0, n_runs=200, policies=("distance",))["distance"]
    assert np.mean(standard["failure_kind"][1] == TOO_LATE) > np.mean(fast["failure_kind"][1] == TOO_LATE)
