"""The railway deployment (docs/model/handover.md §1–2): antennas along the track and A3 as
railways tune it."""

import numpy as np
import pytest

from railradio.handover.params import RAIL_A3, Radio, Scenario, scenario_from_config
from railradio.handover.radio import mean_rsrp_dbm, pattern_loss_db


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
