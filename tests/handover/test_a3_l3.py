"""A3 entering/leaving conditions and the L3 filter against TS 36.331 on hand-made sequences."""

import math

import numpy as np
import pytest

from railradio.handover.a3 import a3_entering, a3_leaving, first_true, held_for, run_length, ttt_samples
from railradio.handover.radio import filtered_gap_noise_std_db, l3_coefficient, l3_coefficient_at, l3_filter


def test_a3_entering_and_leaving_follow_the_inequalities():
    # TS 36.331 5.5.4.4: entering Mn+Ofn+Ocn-Hys > Mp+Ofp+Ocp+Off; leaving Mn+Ofn+Ocn+Hys < Mp+Ofp+Ocp+Off
    mp = -80.0
    mn = np.array([-78.0, -76.9, -77.0, -83.5, -82.9])
    assert a3_entering(mn, mp, 3.0).tolist() == [False, True, False, False, False]
    assert a3_leaving(mn, mp, 3.0).tolist() == [False, False, False, True, False]
    # offsets enter on their sides: Ocn +2 helps the neighbour, Off +2 hinders it
    assert a3_entering(-79.0, mp, 3.0, ocn_db=2.1).item() is True
    assert a3_entering(-79.0, mp, 3.0, ocn_db=2.1, off_db=0.2).item() is False
    assert a3_entering(-79.0, mp, 3.0, ofn_db=1.0, ocp_db=-1.1).item() is True
    assert a3_leaving(-84.0, mp, 3.0, ofp_db=-1.1).item() is False


def test_ttt_sample_count():
    assert ttt_samples(0.0, 0.04) == 1
    assert ttt_samples(0.04, 0.04) == 2
    assert ttt_samples(0.16, 0.04) == 5
    assert ttt_samples(0.256, 0.04) == 8  # 256 ms needs 7 intervals of 40 ms
    with pytest.raises(ValueError):
        ttt_samples(-0.1, 0.04)


def test_held_for_and_run_length_on_a_hand_made_sequence():
    c = np.array([0, 1, 1, 0, 1, 1, 1, 1, 0, 1], dtype=bool)
    assert run_length(c).tolist() == [0, 1, 2, 0, 1, 2, 3, 4, 0, 1]
    assert held_for(c, 3).tolist() == [False] * 6 + [True, True, False, False]
    assert held_for(c, 1).tolist() == c.tolist()
    assert first_true(held_for(c, 4)) == 7
    assert first_true(held_for(c, 5)) == -1


def test_l3_coefficient_matches_the_standard():
    assert l3_coefficient(0) == 1.0
    assert l3_coefficient(4) == 0.5
    assert l3_coefficient(8) == 0.25
    # same time constant at 40 ms: (1 - a')^5 = 1 - a
    a40 = l3_coefficient_at(4, 0.04, 0.2)
    assert (1 - a40) ** 5 == pytest.approx(0.5)
    assert a40 == pytest.approx(0.1294, abs=1e-4)
    assert l3_coefficient_at(4, 0.2, 0.2) == pytest.approx(0.5)


def test_l3_filter_on_a_hand_made_sequence():
    # F_0 = M_1, then F_n = (1 - a) F_{n-1} + a M_n with a = 1/2 (k = 4)
    m = np.array([-80.0, -70.0, -70.0, -90.0])
    f = l3_filter(m, 0.5)
    assert f.tolist() == [-80.0, -75.0, -72.5, -81.25]
    # k = 0: no filtering; batches along leading axes filter independently
    assert l3_filter(m, 1.0).tolist() == m.tolist()
    f2 = l3_filter(np.stack([m, m + 1]), 0.5)
    assert f2[1].tolist() == [-79.0, -74.0, -71.5, -80.25]
    with pytest.raises(ValueError):
        l3_filter(m, 0.0)


def test_filtered_gap_noise_matches_monte_carlo(rng):
    a, s = 0.1294, 1.5
    e = s * rng.standard_normal((2, 400, 2000))
    gap = l3_filter(e[0], a) - l3_filter(e[1], a)
    assert gap[:, 200:].std() == pytest.approx(filtered_gap_noise_std_db(s, a), rel=0.03)
    assert filtered_gap_noise_std_db(1.5, a) == pytest.approx(math.sqrt(2) * 1.5 * math.sqrt(a / (2 - a)))
