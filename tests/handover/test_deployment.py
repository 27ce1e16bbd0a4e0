"""The railway deployment (docs/model/handover.md §1–2): antennas along the track, the
single-frequency cell, and A3 as railways tune it."""

from dataclasses import replace

import numpy as np
import pytest

from railradio.handover.model import build_context, draw_block
from railradio.handover.params import RAIL_A3, Radio, Scenario, scenario_from_config
from railradio.handover.radio import (
    ShadowGrid,
    mean_rsrp_dbm,
    pattern_loss_db,
    rrh_rsrp_dbm,
    sfn_rrh_positions_m,
    sfn_shadowing,
    shadowing_fields,
)
from railradio.handover.train import kinematics


def test_antennas_along_the_track_lose_only_near_their_mast():
    rd = Radio()
    # TR 38.901 Table 7.3-1: 12 (phi/65°)^2, phi = 90° at the mast -> 23.0 dB, 30 dB floor unused
    assert pattern_loss_db(0.0, rd) == pytest.approx(12 * (90 / 65) ** 2)
    assert pattern_loss_db(30.0, rd) == pytest.approx(12 * (45 / 65) ** 2)
    assert pattern_loss_db(-750.0, rd) < 0.02  # the overlap centre: 2.3° off boresight
    omni = Radio(antenna_hpbw_deg=None)
    x = np.array([0.0, 100.0, 750.0])
    d = np.subtract(mean_rsrp_dbm(x, omni), mean_rsrp_dbm(x, rd))
    np.testing.assert_allclose(d[0], pattern_loss_db(x, rd))
    with pytest.raises(ValueError, match="antenna_hpbw_deg"):
        Radio(antenna_hpbw_deg=0.0)


def test_railway_a3_from_the_config_keeps_its_rule():
    scn = scenario_from_config({})
    assert scn.a3_rail == RAIL_A3
    assert (RAIL_A3.l3_k, RAIL_A3.ttt_s, RAIL_A3.hysteresis_db, RAIL_A3.offset_db) == (1, 0.064, 1.0, -2.0)
    scn = scenario_from_config({"a3_rail": {"ttt_s": 0.1}})
    assert scn.a3_rail.ttt_s == 0.1 and scn.a3_rail.l3_k == 1
    with pytest.raises(ValueError, match="l3_k"):
        scenario_from_config({"a3_rail": {"l3_k": 25}})
    assert Scenario().a3.l3_k is None


def test_a_single_frequency_cell_is_the_power_sum_of_its_rrhs():
    rd = Radio(sfn_rrhs=3)
    xs, xt = sfn_rrh_positions_m(rd)
    np.testing.assert_allclose(xs, [0.0, -1500.0, -3000.0])
    np.testing.assert_allclose(xt, [1500.0, 3000.0, 4500.0])
    grid = ShadowGrid(-100.0, 1700.0, 0.5)
    rng = np.random.default_rng(3)
    z0 = 4.0 * rng.standard_normal((64, 2, grid.n))
    zo = 4.0 * rng.standard_normal((64, 2, 2, grid.n))
    eff = sfn_shadowing(z0, zo, grid, rd)
    p = rrh_rsrp_dbm(grid.x_m, rd)  # [G, 2, K]
    for j in range(2):
        each = np.stack([p[:, j, 0] - z0[:, j], p[:, j, 1] - zo[:, j, 0], p[:, j, 2] - zo[:, j, 1]])
        cell = 10 * np.log10(np.sum(10 ** (each / 10), axis=0))
        near = mean_rsrp_dbm(grid.x_m, rd)[j]
        np.testing.assert_allclose(near - eff[:, j], cell, atol=1e-9)
    # the other RRHs only add power: little at the overlap centre (16.7 dB below the nearest
    # there, docs/model/handover.md §9), nothing at a cell's own mast, more beyond the centre
    assert np.all(eff <= z0)
    gain = np.median(z0 - eff, axis=0)  # [2, G]
    assert gain[0, grid.index(0.0)] < 0.01 and gain[1, grid.index(1500.0)] < 0.01
    assert 0.01 < gain[0, grid.index(750.0)] < 0.2 and 0.01 < gain[1, grid.index(750.0)] < 0.2
    assert gain[0, grid.index(1600.0)] > 2 * gain[0, grid.index(750.0)]
    one = Radio()
    assert sfn_shadowing(z0, np.zeros((64, 2, 0, grid.n)), grid, one) is z0
    with pytest.raises(ValueError, match="zeta_other_db"):
        sfn_shadowing(z0, zo[:, :, :1], grid, rd)
    with pytest.raises(ValueError, match="sfn_rrhs"):
        Radio(sfn_rrhs=0)


def test_the_single_frequency_case_leaves_the_nearest_fields_and_every_other_draw():
    scn = Scenario()
    sfn = replace(scn, radio=replace(scn.radio, sfn_rrhs=4))
    kin = kinematics(scn, 350.0)
    draws = draw_block(11, 350.0, 0, 4, kin, scn.train.n_nodes)
    ctx = build_context(scn, kin, draws)
    np.testing.assert_array_equal(ctx.zeta_db, shadowing_fields(draws.field_white, kin.grid, scn.radio))
    ctx_sfn = build_context(sfn, kin, draws)
    assert np.all(ctx_sfn.zeta_db <= ctx.zeta_db)
    assert not np.array_equal(ctx_sfn.zeta_db, ctx.zeta_db)
    # its own stream: another block's other RRHs differ, the same block's are the same
    np.testing.assert_array_equal(draws.sfn_white(3), draw_block(11, 100.0, 0, 4, kin, 8).sfn_white(3))
    assert not np.array_equal(draws.sfn_white(3), draw_block(11, 350.0, 1, 4, kin, 8).sfn_white(3))
