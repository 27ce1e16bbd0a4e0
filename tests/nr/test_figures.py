"""The nr figures' labels: what a reader sees instead of config slugs, and the source's
published values on our curves."""

import pytest

from railradio.nr.study.figures import _source_quantiles
from railradio.nr.study.map_figures import cell_label


@pytest.mark.parametrize(
    ("name", "label"),
    [
        ("mt32_others_random", "M_T = 32, data: others at random beams"),
        ("mt8_none", "M_T = 8, data: none (PSS, SSS only)"),
        ("mt16_my_own_rule", "M_T = 16, data: my own rule"),
        ("tpl_pss_sss_sel_peak", "template PSS+SSS, selection: peak"),
        ("tpl_sss_sel_ss_rsrp", "template SSS, selection: ss-rsrp"),
        ("win2000_none", "window 2 km, data: none (PSS, SSS only)"),
        ("win1500_others_random", "window 1.5 km, data: others at random beams"),
        ("window_geometry", "window_geometry"),
    ],
)
def test_map_rows_read_as_settings(name, label):
    assert cell_label(name) == label


def test_the_source_quantiles_come_from_the_key_specs():
    """p95 1.7 m, p99 2.3 m and 75 % below 1 m (the source's EKF AOD+TOA claims)."""
    assert _source_quantiles("track.aod_toa") == [(1.7, 0.95), (2.3, 0.99), (1.0, 0.75)]
    assert _source_quantiles("track.toa") == []
