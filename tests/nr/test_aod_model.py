"""The AOD's error near endfire (railradio.nr.tracking.aod_model) and its use by the tracker."""

import numpy as np
import pytest

from railradio.nr.tracking import aod_model
from railradio.nr.tracking.calibration import inlier_sigma
from railradio.nr.tracking.ekf import TrackerConfig, run_ekf
from railradio.nr.tracking.imm import ImmConfig, run_imm

EDGES = tuple(np.radians([1.0, 2.0, 5.0]))


def test_angle_from_endfire_and_the_way_to_broadside():
    th = np.radians([-0.5, -3.0, -90.0, -120.0, -179.0])
    psi, t = aod_model.endfire_angle(th)
    np.testing.assert_allclose(np.degrees(psi), [0.5, 3.0, 90.0, 60.0, 1.0], atol=1e-12)
    # broadside (-90°) lies below an angle ahead of the RRH, above one behind it
    np.testing.assert_array_equal(t, [-1, -1, 1, 1, 1])
    np.testing.assert_array_equal(aod_model.bin_index(np.radians([0.5, 1.0, 1.5, 4.0, 30.0]), EDGES), [0, 0, 1, 2, 3])


def test_fit_recovers_a_bias_toward_broadside_by_angle(rng):
    # truth within 5° of endfire, ahead of and behind the RRH; eq. 7's bias toward broadside
    # 1.0° below 1° from endfire, 0.5° from 1° to 2°, none beyond; σ 0.3°; 2 % outliers
    n = 40_000
    psi = np.radians(rng.uniform(0.0, 5.0, n))
    ahead = rng.random(n) < 0.5
    th = np.where(ahead, -psi, -np.pi + psi)
    toward = np.where(ahead, -1.0, 1.0)
    bias = np.radians(np.select([psi <= np.radians(1), psi <= np.radians(2)], [1.0, 0.5], 0.0))
    e = toward * bias + np.radians(0.3) * rng.standard_normal(n)
    out = rng.random(n) < 0.02
    e[out] = np.radians(rng.uniform(-30, 30, out.sum()))
    b, s = aod_model.fit(e, th, EDGES, lambda v: inlier_sigma(v)[0], min_per_bin=50)
    np.testing.assert_allclose(np.degrees(b[:3]), [1.0, 0.5, 0.0], atol=0.02)
    # one spread about the biases, in every bin
    np.testing.assert_allclose(np.degrees(s), [0.3] * 4, rtol=0.05)
    # no data beyond 5°: bias 0
    assert b[3] == 0.0
    # a bin whose errors are mostly outliers keeps the bias of its inliers
    bad = np.concatenate([e, np.radians(rng.uniform(10, 40, 12_000))])
    th_bad = np.concatenate([th, np.full(12_000, -np.radians(0.5))])
    b_bad, _ = aod_model.fit(bad, th_bad, EDGES, lambda v: inlier_sigma(v)[0], min_per_bin=50)
    assert np.degrees(b_bad[0]) == pytest.approx(1.0, abs=0.05)
    # the predicted bias at those angles, turned toward broadside
    at = np.array([-np.radians(0.5), -np.pi + np.radians(1.5), -np.radians(10.0)])
    np.testing.assert_allclose(aod_model.predicted_bias(at, EDGES, b), [-b[0], b[1], 0.0])
    with pytest.raises(ValueError, match="edges_rad"):
        aod_model.fit(e, th, (np.radians(2.0), np.radians(1.0)), np.std)
    with pytest.raises(ValueError, match="shape"):
        aod_model.fit(e, th[:-1], EDGES, np.std)


def _angle_cfg(**kw) -> TrackerConfig:
    return TrackerConfig(
        measurements="aod_toa",
        q=0.1,
        sigma_aod_rad=np.radians(0.6),
        sigma_toa_s=2e-9,
        aod_angle_edges_rad=EDGES,
        aod_bias_bins_rad=tuple(np.radians([1.0, 0.5, 0.3, 0.0])),
        sigma_aod_angle_bins_rad=tuple(np.radians([0.4, 0.3, 0.2, 0.5])),
        **kw,
    )


def test_the_config_predicts_with_the_bias_and_weights_by_angle():
    cfg = _angle_cfg()
    plain = TrackerConfig(measurements="aod_toa", q=0.1, sigma_aod_rad=np.radians(0.6), sigma_toa_s=2e-9)
    # RRHs 15 m beside the track, the train 570 m ahead (1.5° from endfire) and 100 m behind (8.5°)
    dx, dy = np.array([570.0, -100.0]), np.array([-15.0, -15.0])
    h, var = cfg.predict(dx, dy, 7.5)
    h0, var0 = plain.predict(dx, dy, 7.5)
    np.testing.assert_allclose(h[:, 1], h0[:, 1])  # TOAs untouched
    np.testing.assert_allclose(h[:, 0] - h0[:, 0], [-np.radians(0.5), 0.0], atol=1e-15)
    np.testing.assert_allclose(np.sqrt(var[:, 0]), np.radians([0.3, 0.5]))
    np.testing.assert_allclose(var[:, 1], 4e-18)
    assert TrackerConfig.from_record(cfg.record(), measurements="aod_toa") == cfg
    with pytest.raises(ValueError, match="aod_pred_rad"):
        cfg.variances(np.array([400.0]))
    with pytest.raises(ValueError, match="aod_bias_bins_rad"):
        TrackerConfig(aod_angle_edges_rad=EDGES, aod_bias_bins_rad=(0.0,), sigma_aod_angle_bins_rad=(0.1,) * 4)
    with pytest.raises(ValueError, match="sigma_aod_angle_bins_rad"):
        TrackerConfig(aod_angle_edges_rad=EDGES, aod_bias_bins_rad=(0.0,) * 4, sigma_aod_angle_bins_rad=(0.0,) * 4)
    with pytest.raises(ValueError, match="aod_angle_edges_rad"):
        TrackerConfig(aod_angle_edges_rad=(0.1, 2.0), aod_bias_bins_rad=(0.0,) * 3, sigma_aod_angle_bins_rad=(0.1,) * 3)


def test_the_modelled_bias_takes_the_trackers_cross_track_error_away(rng):
    # RRHs every 300 m, 15 m beside the track; the train at 80 m/s on y = 0; each epoch its
    # 3 nearest RRHs measure AOD (biased toward broadside near endfire, as the model says)
    # and TOA. The unbiased model settles beside the track (away from the RRHs: the bias
    # steepens every angle); the modelled bias takes it back.
    cfg = _angle_cfg()
    rrh = np.stack([np.arange(-600.0, 6000.0, 300.0), np.full(22, 15.0)], axis=1)
    dt, n = 0.1, 600
    xs = 80.0 * dt * np.arange(n)

    def measure(k):
        near = np.argsort(np.abs(rrh[:, 0] - xs[k]))[:3]
        dx, dy = xs[k] - rrh[near, 0], -rrh[near, 1]
        h, _ = cfg.predict(dx, dy, 7.5)  # the biased truth
        aod = h[:, 0] + np.radians(0.2) * rng.standard_normal(3)
        toa = h[:, 1] + 1e-9 * rng.standard_normal(3)
        return rrh[near], aod, toa

    meas = [measure(k) for k in range(n)]
    s0 = np.array([0.0, 0.0, 80.0, 0.0, 0.0, 0.0])
    p0 = np.diag([1.0, 1.0, 1.0, 1.0, 0.1, 0.1])
    plain = TrackerConfig(measurements="aod_toa", q=0.1, sigma_aod_rad=np.radians(0.4), sigma_toa_s=2e-9)
    y_plain = run_ekf(lambda k, x: meas[k], dt, 7.5, plain, s0, p0, n)["state"][100:, 1]
    y_model = run_ekf(lambda k, x: meas[k], dt, 7.5, cfg, s0, p0, n)["state"][100:, 1]
    assert abs(np.mean(y_model)) < 0.05 < abs(np.mean(y_plain))
    imm = ImmConfig(q=(0.1, 10.0), sojourn_s=(10.0, 2.0))
    y_imm = run_imm(lambda k, x: meas[k], dt, 7.5, cfg, imm, s0, p0, n)["state"][100:, 1]
    assert abs(np.mean(y_imm)) < 0.05


def test_the_imm_refuses_a_track_bound_config():
    imm = ImmConfig(q=(0.1, 10.0), sojourn_s=(10.0, 2.0))
    with pytest.raises(ValueError, match="track_bound"):
        run_imm(
            lambda k, x: (np.zeros((0, 2)), [], []),
            0.1,
            7.5,
            TrackerConfig(track_bound=True),
            imm,
            np.zeros(6),
            np.eye(6),
            3,
        )
