"""The vectorized engine against the per-step loop reference, noise-free theory, and
independence of the batch split."""

from dataclasses import replace

import numpy as np
import pytest
import xarray as xr

from railradio.handover.a3 import ttt_samples
from railradio.handover.band import band_edges_m, sigma0_and_gaph
from railradio.handover.engine import shard_blocks, simulate_blocks
from railradio.handover.model import build_context, draw_block
from railradio.handover.params import Scenario
from railradio.handover.policies import POLICIES, make_policy, run_policy
from railradio.handover.radio import mean_rsrp_dbm
from railradio.handover.reference import simulate_reference
from railradio.handover.train import kinematics

ALL = ("joint", "a3", "a3_rail", "distance")
COMPARED = (
    "command_x_m",
    "attempts",
    "success",
    "pingpong",
    "delay_s",
    "completion_x_m",
    "rsrp_gap_db",
    "delay_all_s",
    "delay_trigger_s",
)
EX = Scenario().execution


def _scn(**joint):
    base = Scenario().with_weights(3, 0.4)
    return replace(base, joint=replace(base.joint, **joint)) if joint else base


@pytest.mark.parametrize(
    ("speed", "scn"),
    [
        (350.0, _scn()),
        (
            120.0,
            replace(
                _scn(wslr="mean", retry_rule="completed"),
                execution=replace(EX, retry="joint_band", failure_rule="instant"),
            ),
        ),
        (380.0, replace(_scn(), execution=replace(EX, retry="joint_band"))),
        (120.0, replace(_scn(), execution=replace(EX, t304_s=0.1, monitor_s=3.0, report_delay_s=0.0, rlf_t310_s=0.3))),
        (300.0, replace(_scn(), radio=replace(Scenario().radio, fading="rayleigh", q_out_db=-4.0, q_in_db=-2.0))),
        (200.0, replace(_scn(), radio=replace(Scenario().radio, fading="none"))),
        (350.0, replace(_scn(), radio=replace(Scenario().radio, sfn_rrhs=4, spacing_m=1000.0, offset_m=50.0))),
        (460.0, _scn(band_fit="offset", measurements="raw", gaph_rule="narrow")),
        (
            250.0,
            replace(
                Scenario().with_weights(1, 0.5),
                a3=replace(Scenario().a3, ttt_s=0.04),
                execution=replace(EX, failure_rule="instant", max_attempts=10),
            ),
        ),
        (350.0, replace(_scn(), execution=replace(Scenario().execution, failure_rule="rlf"))),
        (
            150.0,
            replace(
                _scn(), execution=replace(Scenario().execution, failure_rule="rlf", rlf_t310_s=0.4, rlf_eval_s=0.12)
            ),
        ),
        (350.0, replace(_scn(), execution=replace(EX, failure_rule="rlm", max_attempts=4, reestablish_s=0.1))),
        (
            100.0,
            replace(
                _scn(),
                execution=replace(Scenario().execution, failure_rule="rlm", rlf_t310_s=0.2, rlm_n310=3, rlm_n311=2),
            ),
        ),
    ],
)
def test_vectorized_engine_equals_the_per_step_loop(speed, scn):
    kin = kinematics(scn, speed)
    draws = draw_block(7, speed, 3, 5, kin, scn.train.n_nodes)
    ctx = build_context(scn, kin, draws)
    ref = simulate_reference(scn, kin, draws, ALL)
    for pol in ALL:
        out = run_policy(make_policy(pol), ctx)
        keys = COMPARED + (("failure_kind",) if scn.execution.failure_rule == "stages" else ())
        for key in keys:
            np.testing.assert_allclose(
                out[key][1].astype(float),
                ref[pol][key].astype(float),
                rtol=1e-9,
                atol=1e-9,
                equal_nan=True,
                err_msg=f"{pol}.{key}",
            )
    # the comparison is not vacuous: some handovers fail, A3 sometimes ping-pongs
    assert 0 < ref["a3"]["success"].mean() < 1 or 0 < ref["joint"]["success"].mean() < 1


def _quiet(**radio):
    base = Scenario().with_weights(3, 0.5)
    rd = replace(base.radio, shadow_sigma_db=0.0, meas_sigma_db=0.0, offset_m=0.01, antenna_hpbw_deg=None, **radio)
    return replace(base, radio=rd, train=replace(base.train, gnss_sigma_m=0.0))


@pytest.mark.parametrize("speed", [100.0, 250.0, 380.0, 500.0])
def test_zero_noise_policies_trigger_where_theory_says(speed):
    """No shadowing, no measurement error, exact positions, no L3 filtering (k = 0)."""
    scn = _quiet(l3_k=0)
    kin = kinematics(scn, speed)
    ctx = build_context(scn, kin, draw_block(1, speed, 0, 2, kin, scn.train.n_nodes))
    x = kin.x_nodes_m
    step = kin.speed_m_s * kin.period_s
    outs = {p: run_policy(make_policy(p), ctx) for p in ALL}
    for pol, out in outs.items():
        assert out["success"][1].all(), pol
        assert not out["pingpong"][1].any(), pol
        assert (out["attempts"][1] == 1).all(), pol
    xc = scn.radio.overlap_centre_m
    d = kin.speed_m_s * scn.execution.report_delay_s  # the command comes report_delay_s after the decision
    # distance: the first sample at or past the overlap centre
    cmd = outs["distance"]["command_x_m"][1] - d
    assert np.all((cmd >= xc - 1e-9) & (cmd < xc + step + 1e-9))
    # A3 (no filter): the first sample where target - serving > Hys, then TTT more samples
    p_s, p_t = mean_rsrp_dbm(x, scn.radio)
    k_enter = np.argmax(p_t - p_s > scn.a3.hysteresis_db, axis=1)
    k_a3 = k_enter + ttt_samples(scn.a3.ttt_s, kin.period_s) - 1
    np.testing.assert_allclose(outs["a3"]["command_x_m"][1] - d, x[np.arange(x.shape[0]), k_a3][None, :].repeat(2, 0))
    # joint: exact fit (a = 0, n = 3.5) -> every node decides at the first sample past
    # Xm = L/2 - v (report delay + T0)
    _, gaph = sigma0_and_gaph(scn.radio, scn.joint)
    pl, pr = band_edges_m(gaph, 0.0, scn.radio.pathloss_exponent, scn.radio)
    xm = 0.5 * (pl + pr) - kin.speed_m_s * scn.execution.lead_s
    cmd = outs["joint"]["command_x_m"][1] - d
    assert np.all((cmd >= xm - 1e-6) & (cmd < xm + step + 1e-6))
    assert np.all(np.abs(outs["joint"]["rsrp_gap_db"][1]) < 0.05 * step + 0.1)


@pytest.mark.parametrize("speed", [150.0, 350.0])
def test_zero_noise_with_l3_filter_never_fails_or_ping_pongs(speed):
    scn = _quiet()
    kin = kinematics(scn, speed)
    ctx = build_context(scn, kin, draw_block(1, speed, 0, 2, kin, scn.train.n_nodes))
    for pol in POLICIES:
        out = run_policy(make_policy(pol), ctx)
        assert out["success"][1].all() and not out["pingpong"][1].any(), pol
    # the filtered A3 triggers after the unfiltered one (filter lag), never before
    a3 = run_policy(make_policy("a3"), ctx)["command_x_m"][1]
    unf = run_policy(
        make_policy("a3"),
        build_context(
            replace(scn, radio=replace(scn.radio, l3_k=0)), kin, draw_block(1, speed, 0, 2, kin, scn.train.n_nodes)
        ),
    )["command_x_m"][1]
    assert np.all(a3 > unf)


def test_results_do_not_depend_on_the_batch_split():
    scn = Scenario().with_weights(2, 0.3)
    whole = simulate_blocks(scn, 300.0, 5, range(0, 4), 6, ALL)
    parts = [simulate_blocks(scn, 300.0, 5, shard_blocks(4, 3, j), 6, ALL) for j in range(3)]
    xr.testing.assert_identical(whole, xr.concat(parts, dim="run", data_vars="minimal"))


def test_shard_blocks_partition():
    blocks = [list(shard_blocks(10, 3, j)) for j in range(3)]
    assert sum(blocks, []) == list(range(10))
    with pytest.raises(ValueError):
        shard_blocks(2, 3, 0)


def test_policy_registry_and_bad_values():
    assert set(POLICIES) == set(ALL)
    with pytest.raises(ValueError, match="policy must be one of"):
        make_policy("a4")
    with pytest.raises(ValueError, match="wslr"):
        replace(Scenario().joint, wslr="median")
    with pytest.raises(ValueError, match="speed_kmh"):
        kinematics(Scenario(), -5.0)
    with pytest.raises(ValueError, match="joint.m and joint.alpha"):
        scn = Scenario()
        kin = kinematics(scn, 300.0)
        make_policy("joint").command(build_context(scn, kin, draw_block(1, 300.0, 0, 1, kin, 8)))


@pytest.mark.parametrize("speed", [150.0, 350.0, 500.0])
def test_zero_noise_l3_filtered_joint_band_has_no_filter_lag(speed):
    """Noise-free with the k = 4 filter: the band fit is exact (â = 0, n̂ = n) and every node
    triggers within one sample of Xm = Xc − v·T0 (the fit regresses filtered gaps against the
    identically filtered regressor, so the filter delay does not shift the band)."""
    scn = _quiet()
    assert scn.radio.l3_k == 4
    kin = kinematics(scn, speed)
    ctx = build_context(scn, kin, draw_block(1, speed, 0, 2, kin, scn.train.n_nodes))
    out = run_policy(make_policy("joint"), ctx)
    np.testing.assert_allclose(out["fit_offset_db"][1], 0.0, atol=1e-6)
    np.testing.assert_allclose(out["fit_exponent"][1], scn.radio.pathloss_exponent, atol=1e-6)
    xm = scn.radio.overlap_centre_m - kin.speed_m_s * scn.execution.t0_s
    _, gaph = sigma0_and_gaph(scn.radio, scn.joint)
    pl, pr = band_edges_m(gaph, 0.0, scn.radio.pathloss_exponent, scn.radio)
    assert abs(0.5 * (pl + pr) - kin.speed_m_s * scn.execution.t0_s - xm) < 0.05  # h ~ 0: Xm = Xc - vT0
    step = kin.speed_m_s * kin.period_s
    cmd = out["command_x_m"][1]
    assert np.all(np.abs(cmd - xm) <= step + 1e-6), (cmd - xm, step)
    assert np.all(out["success"][1] == 1)
    # the completion gap is the one-sample quantization only, as for the distance trigger
    assert np.all(np.abs(out["rsrp_gap_db"][1]) < 10 * 3.5 / np.log(10) * 4 * step / 1500 + 0.05)


def test_rlf_rule_fails_only_after_a_t310_run_of_out_of_sync():
    """Hand-made SINR trace: the serving link fails under ``rlf`` only if every 200 ms mean
    ending within T310 before the command is below Q_out; ``instant`` looks at H_b alone."""
    from railradio.handover.model import rlf_window_samples, serving_ok

    base = _quiet()
    scn = replace(base, execution=replace(base.execution, failure_rule="rlf"))
    assert rlf_window_samples(scn.execution, 0.04) == (5, 25)
    kin = kinematics(scn, 360.0)  # 4 m per sample
    ctx = build_context(scn, kin, draw_block(1, 360.0, 0, 3, kin, scn.train.n_nodes))
    # shadowing field: serving link 30 dB down over [hb - L, hb] (target 0): out of sync there
    hb = 700.0
    x = kin.grid.x_m
    for run, length in enumerate((4.0 * 29 + 1, 4.0 * 24 + 1, -1.0)):  # all 30 samples, j = 0..24, none
        ctx.zeta_db[run, 0, :] = np.where((x <= hb + 0.1) & (x >= hb - length), 30.0, 0.0)
        ctx.zeta_db[run, 1, :] = 0.0
    ok = serving_ok(ctx, np.arange(3), np.full(3, hb))
    np.testing.assert_array_equal(ok, [False, True, True])
    inst = replace(scn, execution=replace(scn.execution, failure_rule="instant"))
    ctx.scn = inst
    np.testing.assert_array_equal(serving_ok(ctx, np.arange(3), np.full(3, hb)), [False, False, True])


@pytest.mark.parametrize("speed", [100.0, 250.0, 350.0, 500.0])
@pytest.mark.parametrize("m", [1, 3])
def test_noise_free_joint_handover_completes_at_zero_rsrp_gap(speed, m):
    """Without shadowing, measurement noise, position error or antenna pattern (the default
    geometry, 30 m offset, and the k = 4 L3 filter), the joint decision's handover *completes* at the point
    where the true mean RSRP gap is zero, within the one-sample quantization of its command,
    and its execution starts v·T0 before that (the band is shifted back by v·(report delay +
    T0), source eq. 2 with the network's report-to-command delay)."""
    base = Scenario().with_weights(m, 0.5)
    scn = replace(
        base,
        radio=replace(base.radio, shadow_sigma_db=0.0, meas_sigma_db=0.0, antenna_hpbw_deg=None),
        train=replace(base.train, gnss_sigma_m=0.0),
    )
    kin = kinematics(scn, speed)
    out = run_policy(make_policy("joint"), build_context(scn, kin, draw_block(1, speed, 0, 2, kin, 8)))
    # the zero of the true mean gap, by bisection on the model
    lo, hi = 1.0, scn.radio.spacing_m - 1.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        p_s, p_t = mean_rsrp_dbm(np.array([mid]), scn.radio)
        lo, hi = (mid, hi) if p_s[0] > p_t[0] else (lo, mid)
    x0 = 0.5 * (lo + hi)
    step = kin.speed_m_s * kin.period_s
    he, hb = out["completion_x_m"][1], out["command_x_m"][1]
    assert np.all(out["success"][1] == 1) and np.all(out["attempts"][1] == 1)
    np.testing.assert_allclose(he - hb, kin.speed_m_s * scn.execution.t0_s, rtol=0, atol=1e-9)
    # the head's band midpoint X_m (decision point) is the zero-gap point shifted back by
    # v·(report delay + T0),
    # up to the fit's model error: the band model omits the 30 m offset, which biases â by
    # <= 0.07 dB here, <= 2 m at the gap's slope of 0.04 dB/m
    xm_done = out["band_xm_m"][1] + kin.speed_m_s * scn.execution.lead_s  # decision + report delay + T0
    assert np.all(np.abs(xm_done - x0) <= 2.0), xm_done - x0
    # every node completes within one sample of that point (its command is the first sample
    # at or past X_m; the predecessors' deviations are zero, so there is no correction)
    assert np.all((he >= xm_done[:, None] - 1e-6) & (he < xm_done[:, None] + step + 1e-6)), (he - x0, step)
    # and the true gap there is that distance times the gap's slope at x0
    slope_db_m = 2 * 10 * scn.radio.pathloss_exponent / np.log(10) * (x0 / (x0**2 + scn.radio.offset_m**2))
    assert np.all(np.abs(out["rsrp_gap_db"][1]) <= slope_db_m * (step + 2.0))
