"""The joint decision's power correction against the truth (railradio.handover.correction)."""

from dataclasses import replace

import numpy as np

from railradio.handover.correction import PARTS, correction_errors, rms_per_node
from railradio.handover.model import build_context, draw_block
from railradio.handover.params import Scenario
from railradio.handover.train import kinematics


def _ctx(scn, speed=250.0, n=40):
    kin = kinematics(scn, speed)
    return build_context(scn, kin, draw_block(3, speed, 0, n, kin, scn.train.n_nodes))


def test_without_noise_or_shadowing_every_deviation_vanishes():
    """No shadowing, no measurement noise, no position error: the true deviations are the
    band model's own misfit (it omits the 30 m offset: < 0.1 dB), the measured ones equal
    them but for the L3 filter's transient (< 0.1 dB), and every prediction is as small."""
    base = Scenario().with_weights(3, 0.5)
    scn = replace(
        base,
        radio=replace(base.radio, shadow_sigma_db=0.0, meas_sigma_db=0.0),
        train=replace(base.train, gnss_sigma_m=0.0),
    )
    out = correction_errors(_ctx(scn), 3, 0.5, scn.joint.wslr)
    for p in ("true", "pred") + PARTS:
        assert np.all(np.isnan(out[p][:, 0]))  # the head has no predecessor
        assert np.nanmax(np.abs(out[p])) < 0.1, p


def test_with_raw_noise_free_measurements_the_correction_is_the_oracle():
    """Shadowing, but raw measurements without noise and no position error: every measured
    deviation is the true one, so the 'measured' column vanishes and the correction equals the
    oracle (the same WSLR on the same deviations); what is left is the deviation's change
    between the predecessors' trigger points and the node's (shadowing decorrelates over
    50 m)."""
    base = Scenario().with_weights(3, 0.5)
    scn = replace(
        base,
        radio=replace(base.radio, meas_sigma_db=0.0),
        train=replace(base.train, gnss_sigma_m=0.0),
        joint=replace(base.joint, measurements="raw"),
    )
    out = correction_errors(_ctx(scn), 3, 0.5, scn.joint.wslr)
    assert np.nanmax(np.abs(out["measured"])) < 1e-9
    np.testing.assert_allclose(out["correction"][:, 1:], out["oracle"][:, 1:], rtol=0, atol=1e-9)
    assert np.nanmean(rms_per_node(out["midpoint"])[1:]) > 1.0  # the shadowing is there to predict
