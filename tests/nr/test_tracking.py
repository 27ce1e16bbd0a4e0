"""Tracker: analytic Jacobians against finite differences, EKF consistency (NEES) on a
simulated case, no NaN when every measurement of an epoch is missing."""

from dataclasses import replace

import numpy as np
import pytest
from scipy.stats import chi2

from railradio.nr.channel.geometry import Trajectory
from railradio.nr.tracking.dynamics import process_noise, transition
from railradio.nr.tracking.ekf import TrackerConfig, run_ekf
from railradio.nr.tracking.measurement import hx, jacobian
from railradio.nr.tracking.snapshot import snapshot_ls

RRH = np.array([[0.0, 15.0], [500.0, 15.0], [-500.0, 15.0]])
DH = 7.5


def _fixed(xy, aod, toa):
    """``select`` of :func:`run_ekf` for measurements fixed in advance (epoch k: ``xy[k]``)."""
    return lambda k, s: (xy[k], aod[k], toa[k])


@pytest.mark.parametrize("measurements", ["aod", "toa", "aod_toa"])
def test_jacobian_matches_finite_differences(measurements):
    s = np.array([123.4, -0.3, 80.0, 0.0, 0.5, 0.0])
    jac = jacobian(s, RRH, DH, measurements)
    h = 1e-4
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        fd = (hx(s + e, RRH, DH, measurements) - hx(s - e, RRH, DH, measurements)) / (2 * h)
        np.testing.assert_allclose(jac[:, j], fd, rtol=1e-6, atol=1e-12)


def test_transition_and_process_noise():
    f = transition(0.1)
    s = np.array([0.0, 0.0, 10.0, 0.0, 2.0, 0.0])
    np.testing.assert_allclose(f @ s, [1.0 + 0.01, 0.0, 10.2, 0.0, 2.0, 0.0])
    q = process_noise(0.1, 2.0)
    assert np.allclose(q, q.T) and np.all(np.linalg.eigvalsh(q) > -1e-15)
    assert q[4, 4] == pytest.approx(2.0 * 0.1)  # acceleration variance grows q·T


_SIG_AOD_RAD = np.radians(0.5)


def _simulate(rng, n=600, dt=0.1, q=0.5, sig_aod=_SIG_AOD_RAD, sig_toa=2e-9):
    """A constant-acceleration truth driven by white jerk along x (y = 0), noisy measurements."""
    f = transition(dt)
    qm = process_noise(dt, q)
    qm[1::2, :] = 0
    qm[:, 1::2] = 0
    s = np.array([-300.0, 0.0, 60.0, 0.0, 0.0, 0.0])
    truth, meas = [], []
    chol = np.linalg.cholesky(qm[0::2, 0::2] + 1e-18 * np.eye(3))
    cfg = TrackerConfig(measurements="aod_toa", q=q, sigma_aod_rad=sig_aod, sigma_toa_s=sig_toa)
    for _ in range(n):
        s = f @ s
        s[0::2] += chol @ rng.standard_normal(3)
        z = hx(s, RRH, DH, "aod_toa") + np.tile([sig_aod, sig_toa], 3) * rng.standard_normal(6)
        truth.append(s.copy())
        meas.append(z)
    return np.array(truth), meas, cfg


def test_ekf_is_consistent_on_a_simulated_case():
    """Mean NEES of the position over the run within its χ² 99 % interval."""
    rng = np.random.default_rng(8)
    truth, meas, cfg = _simulate(rng)
    xy = [RRH] * len(meas)
    aod = [m[0::2] for m in meas]
    toa = [m[1::2] for m in meas]
    s0 = truth[0] + np.array([1.0, 0.5, 0, 0, 0, 0])
    p0 = np.diag([4.0, 4.0, 4.0, 4.0, 1.0, 1.0])
    out = run_ekf(_fixed(xy, aod, toa), 0.1, DH, cfg, s0, p0, len(xy))
    err = out["state"][:, :2] - truth[:, :2]
    # y is truly fixed at 0 while the filter lets it move: use the x component (1 dof)
    nees = err[100:, 0] ** 2 / out["cov"][100:, 0, 0]
    n = nees.size
    lo, hi = chi2.ppf([0.005, 0.995], n) / n
    # epochs are correlated, so the effective n is smaller: widen by a factor 2 around 1
    assert lo / 2 < nees.mean() < hi * 2, nees.mean()
    assert np.sqrt(np.mean(err[100:, 0] ** 2)) < 1.0


def test_missing_measurements_predict_without_nan():
    rng = np.random.default_rng(9)
    truth, meas, cfg = _simulate(rng, n=50)
    xy = [RRH if k % 5 else np.zeros((0, 2)) for k in range(50)]
    aod = [m[0::2] if k % 5 else np.zeros(0) for k, m in enumerate(meas)]
    toa = [m[1::2] if k % 5 else np.zeros(0) for k, m in enumerate(meas)]
    out = run_ekf(_fixed(xy, aod, toa), 0.1, DH, cfg, truth[0], np.eye(6), len(xy))
    assert np.all(np.isfinite(out["state"])) and np.all(np.isfinite(out["cov"]))
    assert np.all(np.isnan(out["nis"][::5])) and np.all(out["n_used"][::5] == 0)


def test_gate_rejects_an_outlier():
    rng = np.random.default_rng(10)
    truth, meas, _ = _simulate(rng, n=30)
    cfg = TrackerConfig(measurements="toa", q=0.5, sigma_toa_s=2e-9, gate=True)
    toa = [m[1::2].copy() for m in meas]
    toa[20][1] += 5000 / 3e8  # a 5 km TOA outlier on one RRH
    out = run_ekf(_fixed([RRH] * 30, [m[0::2] for m in meas], toa), 0.1, DH, cfg, truth[0], np.eye(6), 30)
    assert out["n_used"][20] == 2
    assert abs(out["state"][20, 0] - truth[20, 0]) < 5.0


def test_track_bound_filter_holds_the_train_on_the_track():
    """The track-bound EKF keeps y, v_y, a_y and their covariances exactly 0 (also through a
    start off the track and a re-acquisition), its along-track NEES is χ²₁-consistent, and with
    TOAs alone it does not take the mirror side of the RRH line the free filter can take."""
    from railradio.nr.tracking.ekf import LATERAL, nees_position

    rng = np.random.default_rng(11)
    truth, meas, cfg = _simulate(rng)
    xy = [RRH] * len(meas)
    aod = [m[0::2] for m in meas]
    toa = [m[1::2] for m in meas]
    s0 = truth[0] + np.array([1.0, 0.5, 0, 0.3, 0, 0.1])  # off the track: y is reset to 0
    p0 = np.diag([4.0, 4.0, 4.0, 4.0, 1.0, 1.0])
    tb = replace(cfg, track_bound=True)
    out = run_ekf(_fixed(xy, aod, toa), 0.1, DH, tb, s0, p0, len(xy))
    assert np.all(out["state"][:, LATERAL] == 0.0)
    assert np.all(out["cov"][:, LATERAL, :] == 0.0) and np.all(out["cov"][:, :, LATERAL] == 0.0)
    nees = nees_position(out["state"], out["cov"], truth[:, 0], track_bound=True)[100:]
    n = nees.size
    lo, hi = chi2.ppf([0.005, 0.995], n) / n
    assert lo / 2 < nees.mean() < hi * 2, nees.mean()
    np.testing.assert_allclose(nees, (out["state"][100:, 0] - truth[100:, 0]) ** 2 / out["cov"][100:, 0, 0])

    # TOAs alone from RRHs on one side, started on the mirror side (y = 30 m): the free filter
    # stays there, the track-bound one cannot
    toa_only = TrackerConfig(measurements="toa", q=cfg.q, sigma_toa_s=cfg.sigma_toa_s)
    mirror = truth[0] + np.array([0.0, 30.0, 0, 0, 0, 0])
    free = run_ekf(_fixed(xy, aod, toa), 0.1, DH, toa_only, mirror, p0, len(xy))
    bound = run_ekf(_fixed(xy, aod, toa), 0.1, DH, replace(toa_only, track_bound=True), mirror, p0, len(xy))
    assert np.median(np.abs(free["state"][100:, 1])) > 20.0
    assert np.sqrt(np.mean((bound["state"][100:, 0] - truth[100:, 0]) ** 2)) < 1.0

    # a re-acquisition moves x alone: every measurement rejected for 10 epochs, then a fix
    gated = replace(tb, gate=True)
    far = [t + 5000 / 3e8 for t in toa]  # every TOA 5 km off: all rejected
    fix = (np.array([truth[20, 0] + 2.0, 7.0]), np.array([[9.0, 1.0], [1.0, 16.0]]))
    got = run_ekf(_fixed(xy, aod, far), 0.1, DH, gated, truth[0], p0, 30, reacquire=lambda k: fix)
    k = int(np.flatnonzero(got["reacquired"])[0])
    assert got["state"][k, 0] == fix[0][0] and got["cov"][k, 0, 0] == 9.0
    assert np.all(got["state"][:, LATERAL] == 0.0) and np.all(got["cov"][:, LATERAL, :] == 0.0)


def test_snapshot_ls_recovers_noiseless_position():
    cfg = TrackerConfig(measurements="aod_toa")
    p_true = np.array([210.0, 0.0])
    s = np.r_[p_true, np.zeros(4)]
    z = hx(s, RRH, DH, "aod_toa")
    p, cov = snapshot_ls(RRH, z[0::2], z[1::2], DH, cfg, np.array([150.0, 5.0]))
    np.testing.assert_allclose(p, p_true, atol=1e-6)
    assert np.all(np.linalg.eigvalsh(cov) > 0)


def test_trajectory_source_profile():
    tr = Trajectory(((200, 0.5), (27.5, 0.0), (150, 0.2), (200, -0.65)))
    x, v, a = tr.state(np.array([0.0, 200.0, 227.5, 377.5, 577.5]))
    np.testing.assert_allclose(x, [0, 10_000, 12_750, 30_000, 43_000])
    np.testing.assert_allclose(v * 3.6, [0, 360, 360, 468, 0], atol=1e-9)
    assert tr.n_epochs == 5775
    with pytest.raises(ValueError):
        Trajectory(((0.0, 1.0),))


def test_toa_crb_and_peb_against_hand_values():
    from railradio.nr.tracking.bounds import BETA_RMS_HZ, INTEGER_SAMPLE_SIGMA_M, peb_m, toa_crb_s

    assert BETA_RMS_HZ == pytest.approx(8.8e6, rel=0.01)  # docs/model/nr.md §7
    assert INTEGER_SAMPLE_SIGMA_M == pytest.approx(0.352, abs=1e-3)
    # E/N0 = 1e4 (40 dB): σ_τ = 1/(2π · 8.8 MHz · sqrt(2e4)) = 0.128 ns
    assert float(toa_crb_s(1e4)) == pytest.approx(1 / (2 * np.pi * BETA_RMS_HZ * np.sqrt(2e4)))
    # one RRH straight ahead on the track line (no height): range gives x, angle gives y
    xy = np.array([[100.0, 0.0]])
    peb = peb_m(xy, 0.0, 0.0, np.array([0.3]), 0.01)
    assert peb == pytest.approx(np.hypot(0.3, 100 * 0.01), rel=1e-9)


def test_pcrb_settles_below_the_snapshot_peb():
    """With the same geometry and error levels, the recursion integrates the epochs: it
    starts at the one-epoch information and settles below the snapshot PEB of every epoch."""
    from railradio.constants import SPEED_OF_LIGHT_M_S
    from railradio.nr.tracking.bounds import pcrb_m, peb_m

    n = 200
    xy = [RRH] * n
    x = 50.0 + 0.1 * np.arange(n)
    s_toa = 1e-9
    out = pcrb_m(xy, x, DH, [np.full(3, s_toa)] * n, 0.01, 0.1, 0.1, np.eye(6) * 100)
    peb = np.array([peb_m(RRH, float(xk), DH, np.full(3, SPEED_OF_LIGHT_M_S * s_toa), 0.01) for xk in x])
    assert out[0] < 10 and np.all(np.diff(out[5:]) < 1e-3)  # non-increasing once informed
    assert out[0] == pytest.approx(peb[0], rel=0.05)  # one epoch: the snapshot information (and a weak prior)
    assert np.all(out[20:] < 0.7 * peb[20:])  # ten epochs a second (q = 0.1): 40-55 % below the snapshot PEB


def test_toa_crb_counts_the_detected_blocks_against_the_other_ss_blocks():
    """The bound's E/N0 is the sum over the blocks above the detection level of E_b over
    noise plus the other links' SS blocks of the same index; a block below that level adds
    nothing; another link's data beam does not enter (it fills other symbols)."""
    from railradio.nr.channel.link import Links
    from railradio.nr.tracking.bounds import DETECT_E_OVER_N0, PSS_SSS_SUBCARRIERS, block_e_over_n0, burst_e_over_n0
    from railradio.nr.waveform.numerology import SUBCARRIER_SPACING_HZ

    assert 10 * np.log10(DETECT_E_OVER_N0) == pytest.approx(8.75, abs=0.01)
    n0 = 1e-20
    beams = np.array([[1.0, 0.1, 1e-3], [0.5, 1.0, 1e-3]])
    links = Links(
        n_id1=np.zeros(2, int),
        n_id2=np.array([0, 1]),
        tau_s=np.zeros(2),
        amp=np.array([1e-6, 1e-6]),
        beam_amp=beams,
        data_amp=np.array([1e3, 1e3]),
        f_los_hz=np.zeros(2),
        phase0=np.zeros(2),
        doppler_hz=0.0,
        noise_psd_w_hz=n0,
        n_chains=2,
    )
    e = block_e_over_n0(links)
    t_u = 1 / SUBCARRIER_SPACING_HZ
    p = (1e-6 * beams) ** 2
    want = 2 * PSS_SSS_SUBCARRIERS * p * t_u / (2 * n0 + p[::-1] * t_u)
    np.testing.assert_allclose(e, want, rtol=1e-12)
    assert e[0, 2] < DETECT_E_OVER_N0 < e[0, 0]
    total = burst_e_over_n0(links)
    np.testing.assert_allclose(total, np.where(want >= DETECT_E_OVER_N0, want, 0).sum(axis=1), rtol=1e-12)


def test_pcrb_true_motion_bound_orders_and_resets():
    """q = 0 (constant acceleration) bounds below any q > 0; an unknown acceleration jump
    raises the bound right after it; a negative q is rejected."""
    from railradio.nr.tracking.bounds import change_epochs, pcrb_m

    n = 300
    xy = [RRH] * n
    x = 50.0 + 0.1 * np.arange(n)
    args = (xy, x, DH, [np.full(3, 1e-9)] * n, 0.01, 0.1)
    p0 = np.eye(6) * 100
    white = pcrb_m(*args, 1.0, p0)
    const = pcrb_m(*args, 0.0, p0)
    jump = pcrb_m(*args, 0.0, p0, reset_epochs=[150])
    assert np.all(const <= white + 1e-12) and const[-1] < 0.5 * white[-1]
    np.testing.assert_array_equal(jump[:150], const[:150])
    assert np.all(jump[151:] >= const[151:] - 1e-12) and jump[160] > const[160]
    with pytest.raises(ValueError, match="q"):
        pcrb_m(*args, -1.0, p0)
    np.testing.assert_array_equal(change_epochs(((20.0, 0.5), (2.75, 0.0), (3.0, 1.0)), 0.1), [200, 228])


def test_distance_dependent_measurement_noise():
    cfg = TrackerConfig(
        measurements="aod_toa",
        q=1.0,
        sigma_aod_rad=0.02,
        sigma_toa_s=1e-9,
        distance_edges_m=(300.0, 800.0),
        sigma_aod_bins_rad=(0.05, 0.02, 0.01),
        sigma_toa_bins_s=(1e-9, 2e-9, 4e-9),
    )
    w = np.diag(cfg.noise(3, np.array([10.0, 500.0, 2000.0])))
    np.testing.assert_allclose(w, [0.05**2, 1e-18, 0.02**2, 4e-18, 0.01**2, 16e-18])
    # without distances (or bins) the constant W
    np.testing.assert_allclose(np.diag(cfg.noise(1)), [0.02**2, 1e-18])
    back = TrackerConfig.from_record(cfg.record(), measurements="aod_toa")
    assert back == cfg
    with pytest.raises(ValueError, match="sigma_toa_bins_s"):
        TrackerConfig(distance_edges_m=(300.0,), sigma_aod_bins_rad=(0.1, 0.1), sigma_toa_bins_s=(1e-9,))
    with pytest.raises(ValueError, match="distance_edges_m"):
        TrackerConfig(distance_edges_m=(300.0, 100.0), sigma_aod_bins_rad=(1, 1, 1), sigma_toa_bins_s=(1, 1, 1))


def test_robust_sigmas_per_distance_bin():
    from railradio.nr.tracking.calibration import robust_sigmas

    rng = np.random.default_rng(3)
    dist = rng.uniform(0, 1500, 20000)
    e_rng = rng.standard_normal(dist.size) * np.where(dist < 500, 1.0, 3.0)
    e_rng[:200] = 5e3  # 1 % outliers barely move a MAD
    e_aod = rng.standard_normal(dist.size) * 0.01
    s_aod, s_toa, bins = robust_sigmas(e_aod, e_rng, dist, (500.0,), fs_hz=245.76e6)
    c = 299_792_458.0
    assert bins["sigma_toa_bins_s"][0] * c == pytest.approx(1.0, rel=0.06)
    assert bins["sigma_toa_bins_s"][1] * c == pytest.approx(3.0, rel=0.06)
    assert 1.0 < s_toa * c < 3.0 and s_aod == pytest.approx(0.01, rel=0.05)
    # a sparse bin falls back to the overall values; the TOA floor is the quantization
    _, _, b2 = robust_sigmas(e_aod, e_rng * 0, dist, (1499.9,), fs_hz=245.76e6)
    assert b2["sigma_toa_bins_s"][1] == pytest.approx(1 / (np.sqrt(12) * 245.76e6))
    assert robust_sigmas(e_aod, e_rng, dist)[2] == {}


def test_select_measurements_equals_nearest_by_full_sort():
    """The windowed nearest-RRH search picks the same columns as a stable argsort over
    every RRH: midpoint ties, ends of the track, far-off and NaN predictions included."""
    from railradio.nr.tracking.candidates import select_measurements

    rrh_x = np.arange(87) * 500.0
    rng = np.random.default_rng(7)
    xs = np.concatenate(
        [
            rng.uniform(-3000, 46000, 300),
            np.arange(87) * 500.0 + 250.0,
            np.arange(87) * 500.0,
            [np.nan, 1e20, -1e20, 5e8, -7e8, -0.0],
        ]
    )
    for x in xs:
        cand = rng.choice(87, 6, replace=False)
        ok = rng.random(6) < 0.8
        strength = rng.random(6)
        near = set(np.argsort(np.abs(rrh_x - x), kind="stable")[:6].tolist())
        cols = sorted((c for c in range(6) if ok[c] and int(cand[c]) in near), key=lambda c: -strength[c])
        np.testing.assert_array_equal(
            select_measurements(cand, ok, strength, rrh_x, x, 6, 3), np.array(cols[:3], dtype=np.int64)
        )


def test_snapshot_batch_equals_one_epoch_at_a_time():
    """snapshot_ls_batch over padded epochs gives each epoch's own fix."""
    from railradio.nr.tracking.snapshot import snapshot_ls_batch

    rng = np.random.default_rng(3)
    cfg = TrackerConfig(measurements="aod_toa", sigma_aod_rad=np.radians(1.0), sigma_toa_s=2e-9)
    xy_all = np.full((4, 3, 2), np.nan)
    a_all, t_all, guess = np.full((4, 3), np.nan), np.full((4, 3), np.nan), np.zeros((4, 2))
    for e, m in enumerate((3, 2, 1, 3)):
        s = np.array([rng.uniform(100, 900), 0.0, 0, 0, 0, 0])
        xy = RRH[:m]
        z = hx(s, xy, DH, "aod_toa") + np.tile([1e-3, 1e-9], m) * rng.standard_normal(2 * m)
        xy_all[e, :m], a_all[e, :m], t_all[e, :m] = xy, z[0::2], z[1::2]
        guess[e] = s[:2] + [3.0, 2.0]
    p, cov = snapshot_ls_batch(xy_all, a_all, t_all, DH, cfg, guess, with_cov=True)
    for e, m in enumerate((3, 2, 1, 3)):
        p1, c1 = snapshot_ls(xy_all[e, :m], a_all[e, :m], t_all[e, :m], DH, cfg, guess[e])
        np.testing.assert_allclose(p[e], p1, rtol=0, atol=1e-9)
        np.testing.assert_allclose(cov[e], c1, rtol=1e-9)
    with pytest.raises(ValueError, match="rrh_xy"):
        snapshot_ls_batch(np.full((1, 3, 2), np.nan), a_all[:1], t_all[:1], DH, cfg, guess[:1])


TRUTH_VARS = ("x_true", "v_true", "a_true", "d3d", "toa_true", "aod_true", "rx_power", "sir_best")
"""What the simulation knows and a receiver does not (the candidate list is the receiver's
own, tests/nr/test_cellsearch.py)."""


def test_the_tracker_sees_no_truth():
    """track() gives the same tracks, snapshot fixes and NIS when every truth array of the
    estimates is replaced by NaN and the candidates of each epoch are shuffled: it starts
    and re-acquires from its own measurements (the strongest measured cell), not from the
    stored order of the candidates."""
    import yaml

    from railradio.nr.engine.epochs import simulate_epochs
    from railradio.nr.engine.simulate import scenario_from_config
    from railradio.nr.tracking.track import track
    from railradio.rng import spawn_key

    from ..conftest import ROOT

    nr = yaml.safe_load((ROOT / "config/config.yaml").read_text())["nr"]
    scn = scenario_from_config(nr)
    ds = simulate_epochs(scn, np.arange(2500, 2560), 7, spawn_key("nr", 0)).sel(receiver="robust")
    blind = ds.copy()
    for name in TRUTH_VARS:
        blind[name] = ds[name].copy(data=np.full(ds[name].shape, np.nan))
    perm = np.argsort(np.random.default_rng(3).random((ds.sizes["epoch"], ds.sizes["cand"])), axis=1)
    for name, var in blind.data_vars.items():
        if var.dims == ("epoch", "cand"):
            blind[name] = var.copy(data=np.take_along_axis(var.values, perm, axis=1))
    assert not np.array_equal(blind["rrh"].values, ds["rrh"].values)
    dep = scn.deployment
    for measurements in ("aod", "toa", "aod_toa"):
        for gate in (False, True):
            cfg = TrackerConfig(
                measurements=measurements, q=1.0, sigma_aod_rad=np.radians(2.0), sigma_toa_s=4e-9, gate=gate
            )
            args = (dep.x_m, dep.offset_m, dep.h_bs_m - dep.h_ut_m, scn.trajectory.dt_s, cfg)
            a, b = track(ds, *args, strength="best_score"), track(blind, *args, strength="best_score")
            for key in ("state", "nis", "snapshot", "n_used", "reacquired"):
                np.testing.assert_array_equal(a[key], b[key], err_msg=f"{measurements} gate={gate}: {key}")
            assert np.isfinite(a["state"][-1, 0])


def test_inlier_sigma_ignores_outliers_a_mad_does_not():
    """40 % of gross errors (another RRH's peak): the inliers' σ is recovered to 3 %, while
    1.4826 · MAD is inflated by more than a third."""
    from railradio.nr.tracking.calibration import inlier_sigma

    rng = np.random.default_rng(11)
    e = np.concatenate([rng.standard_normal(12000) * 2.0, rng.uniform(-3000, 3000, 8000)])
    sig, frac = inlier_sigma(e, 0.99)
    assert sig == pytest.approx(2.0, rel=0.03)
    assert frac == pytest.approx(0.6, abs=0.01)
    assert 1.4826 * np.median(np.abs(e - np.median(e))) > 1.33 * 2.0
    assert inlier_sigma(np.zeros(10))[0] == 0.0


def test_nees_position_is_the_quadratic_form():
    from railradio.nr.tracking.ekf import nees_position

    rng = np.random.default_rng(2)
    state = rng.standard_normal((5, 6))
    a = rng.standard_normal((5, 6, 6))
    cov = a @ np.swapaxes(a, 1, 2) + np.eye(6)
    x = rng.standard_normal(5)
    e = np.stack([state[:, 0] - x, state[:, 1]], axis=1)
    ref = np.einsum("ei,eij,ej->e", e, np.linalg.inv(cov[:, :2, :2]), e)
    np.testing.assert_allclose(nees_position(state, cov, x), ref, rtol=1e-10)
    state[0] = np.nan
    assert np.isnan(nees_position(state, cov, x)[0])


def test_q_search_widens_past_a_winning_edge_and_reports_monotone_costs(monkeypatch):
    """When the grid's edge wins, the calibration tries decades beyond it; a cost that keeps
    falling to the search limit is reported as monotone and on the edge."""
    from railradio.nr.tracking import calibration as cal

    monkeypatch.setattr(
        cal,
        "measurement_errors",
        lambda ds, strength, with_distance: (np.full(100, 0.01), np.full(100, 1.0), np.full(100, 100.0)),
    )
    monkeypatch.setattr(cal, "track", lambda ds, *a, cfg=None, **k: {"q": a[4].q} if cfg is None else {"q": cfg.q})
    args = (None, "aod_toa", np.arange(3) * 500.0, 15.0, 7.5, 0.1)
    for optimum, edge in ((1e3, False), (1e9, True)):
        monkeypatch.setattr(cal, "_nees_cost", lambda ds, out, o=optimum: abs(np.log10(out["q"] / o)))
        search = {}
        cfg = cal.calibrate(*args, q_grid=np.array([0.01, 1.0, 100.0]), gate=True, search=search)
        assert cfg.q == (optimum if not edge else cal.Q_SEARCH_LIMITS[1])
        assert search["at_edge"] is edge and search["monotone"] is edge
        assert max(search["q"]) == (1e4 if not edge else cal.Q_SEARCH_LIMITS[1])


def test_q_search_monotone_means_falling_to_the_limit_from_the_grid_edge(monkeypatch):
    """A cost that wobbles inside the grid but falls at every decade from the grid's edge to
    the search limit is monotone toward the edge (no q identified); a flat cost, whose
    tie-break walks to the lower limit, is on the edge but not monotone."""
    from railradio.nr.tracking import calibration as cal

    monkeypatch.setattr(
        cal,
        "measurement_errors",
        lambda ds, strength, with_distance: (np.full(100, 0.01), np.full(100, 1.0), np.full(100, 100.0)),
    )
    monkeypatch.setattr(cal, "track", lambda ds, *a, cfg=None, **k: {"q": a[4].q} if cfg is None else {"q": cfg.q})
    args = (None, "aod_toa", np.arange(3) * 500.0, 15.0, 7.5, 0.1)
    wobble = {0.01: 12.0, 1.0: 12.5, 100.0: 7.0}
    monkeypatch.setattr(cal, "_nees_cost", lambda ds, out: wobble.get(out["q"], abs(np.log10(out["q"] / 1e9))))
    search = {}
    cal.calibrate(*args, q_grid=np.array([0.01, 1.0, 100.0]), gate=True, search=search)
    assert search["at_edge"] and search["monotone"]
    monkeypatch.setattr(cal, "_nees_cost", lambda ds, out: 1.0)
    search = {}
    cfg = cal.calibrate(*args, q_grid=np.array([0.01, 1.0, 100.0]), gate=True, search=search)
    assert cfg.q == pytest.approx(cal.Q_SEARCH_LIMITS[0]) and search["at_edge"] and not search["monotone"]
