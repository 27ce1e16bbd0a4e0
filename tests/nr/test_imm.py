"""IMM filter, RTS smoother and the lag key numbers (docs/model/nr.md §6)."""

import json

import numpy as np
import pytest
import xarray as xr
from filterpy.kalman import KalmanFilter

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.study.imm_report import change_windows, key_numbers
from railradio.nr.tracking.dynamics import process_noise, transition
from railradio.nr.tracking.ekf import TrackerConfig, run_ekf
from railradio.nr.tracking.imm import (
    ImmConfig,
    markov_matrix,
    position_nees,
    q_for_jump,
    run_imm,
    stationary,
    track_filters,
)
from railradio.nr.tracking.smoother import rts_smooth
from railradio.nr.tracking.track import track

DT = 0.1
DH = 7.5
RRH_Y = 15.0
SIG_AOD = np.radians(0.5)
SIG_TOA = 0.3 / SPEED_OF_LIGHT_M_S


def _truth(acc: list[tuple[float, float]], v0: float = 80.0, x0: float = 1000.0):
    """Piecewise-constant acceleration along x (y = 0): x [n], a [n]."""
    a = np.concatenate([np.full(int(round(d / DT)), ai) for d, ai in acc])
    v = v0 + np.concatenate([[0.0], np.cumsum(a[:-1]) * DT])
    x = x0 + np.concatenate([[0.0], np.cumsum(v[:-1] * DT + 0.5 * a[:-1] * DT**2)])
    return x, a


def _measure(x: np.ndarray, rng, rrh_x: np.ndarray, n_use: int = 3):
    """AOD/TOA of the ``n_use`` RRHs nearest the truth, with Gaussian noise."""
    xy, aod, toa = [], [], []
    for xk in x:
        idx = np.sort(np.argsort(np.abs(rrh_x - xk))[:n_use])
        p = np.stack([rrh_x[idx], np.full(n_use, RRH_Y)], axis=1)
        dx, dy = xk - p[:, 0], 0.0 - p[:, 1]
        xy.append(p)
        aod.append(np.arctan2(dy, dx) + SIG_AOD * rng.standard_normal(n_use))
        toa.append(np.sqrt(dx**2 + dy**2 + DH**2) / SPEED_OF_LIGHT_M_S + SIG_TOA * rng.standard_normal(n_use))
    return xy, aod, toa


def _cfg(q: float, gate: bool = True) -> TrackerConfig:
    return TrackerConfig(measurements="aod_toa", q=q, sigma_aod_rad=SIG_AOD, sigma_toa_s=SIG_TOA, gate=gate)


def _s0(x, v0=80.0):
    return np.array([x[0], 0.0, v0, 0.0, 0.0, 0.0]), np.diag([1.0, 1.0, 1.0, 1.0, 1.0, 1.0])


def _select(xy, aod, toa):
    return lambda k, s: (xy[k], aod[k], toa[k])


# ---- parameters ----------------------------------------------------------------------


def test_markov_matrix_sojourn_and_stationary():
    pi = markov_matrix([100.0, 1.0], DT)
    np.testing.assert_allclose(pi.sum(axis=1), 1.0)
    np.testing.assert_allclose(np.diag(pi), [1 - DT / 100.0, 1 - DT / 1.0])
    mu = stationary(pi)
    np.testing.assert_allclose(mu @ pi, mu, atol=1e-12)
    np.testing.assert_allclose(mu, [100.0 / 101.0, 1.0 / 101.0], rtol=1e-9)  # time share ∝ sojourn
    # a simulated chain's mean sojourn in mode 1 is the stated 1 s (geometric, mean dt/(1-p11))
    rng = np.random.default_rng(7)
    runs = rng.geometric(1 - pi[1, 1], size=20000) * DT
    assert abs(runs.mean() - 1.0) < 0.03
    np.testing.assert_array_equal(markov_matrix([5.0], DT), [[1.0]])


def test_q_for_jump_rule():
    assert q_for_jump(1.0, 0.1) == pytest.approx(10.0)
    # the rule: the white-jerk acceleration variance accumulated over T is q T = Δa²
    q = q_for_jump(0.85, 0.1)
    assert process_noise(0.1, q)[4, 4] == pytest.approx(0.85**2)


@pytest.mark.parametrize(
    "kwargs, word",
    [
        ({"q": (), "sojourn_s": ()}, "q"),
        ({"q": (0.01, -1.0), "sojourn_s": (100.0, 1.0)}, "q"),
        ({"q": (0.01, 10.0), "sojourn_s": (100.0,)}, "sojourn_s"),
        ({"q": (0.01, 10.0), "sojourn_s": (100.0, 0.0)}, "sojourn_s"),
        ({"q": (0.01, 10.0), "sojourn_s": (100.0, 1.0), "mu0": (0.5, 0.6)}, "mu0"),
    ],
)
def test_imm_config_rejects_bad_values(kwargs, word):
    with pytest.raises(ValueError, match=word):
        ImmConfig(**kwargs)


def test_bad_parameters_raise():
    with pytest.raises(ValueError, match="sojourn_s"):
        markov_matrix([100.0, 0.05], DT)  # shorter than one interval
    with pytest.raises(ValueError, match="dt_s"):
        markov_matrix([100.0, 1.0], 0.0)
    with pytest.raises(ValueError, match="delta_a_m_s2"):
        q_for_jump(0.0, DT)
    with pytest.raises(ValueError, match="states"):
        rts_smooth(np.zeros((5, 6)), np.zeros((5, 6)), np.eye(6), np.eye(6))
    with pytest.raises(ValueError, match="f and q"):
        rts_smooth(np.zeros((5, 6)), np.zeros((5, 6, 6)), np.eye(5), np.eye(6))
    s0, p0 = _s0([0.0])
    with pytest.raises(ValueError, match="reacquire_after"):
        run_imm(
            lambda k, s: (np.zeros((0, 2)), [], []),
            DT,
            DH,
            _cfg(1.0),
            ImmConfig((1.0,), (1.0,)),
            s0,
            p0,
            3,
            reacquire_after=0,
        )
    with pytest.raises(ValueError, match="window_s"):
        change_windows(_report_ds(), 0.0)


# ---- the IMM -------------------------------------------------------------------------


def test_single_model_imm_equals_ekf():
    """One model: mixing is the identity and every step is the EKF's (filterpy) update."""
    rng = np.random.default_rng(11)
    x, _ = _truth([(20.0, 0.5), (20.0, -0.65)])
    rrh_x = np.arange(0.0, 5000.0, 500.0)
    xy, aod, toa = _measure(x, rng, rrh_x)
    toa[50] = toa[50] + np.array([30.0, 0.0, 0.0]) / SPEED_OF_LIGHT_M_S  # an outlier the gate must reject
    for k in range(100, 115):  # a stretch with no measurements
        xy[k], aod[k], toa[k] = np.zeros((0, 2)), np.array([]), np.array([])
    s0, p0 = _s0(x)
    for gate in (False, True):
        cfg = _cfg(0.3, gate)
        ref = run_ekf(_select(xy, aod, toa), DT, DH, cfg, s0, p0, len(xy))
        got = run_imm(_select(xy, aod, toa), DT, DH, cfg, ImmConfig((0.3,), (10.0,)), s0, p0, len(xy))
        np.testing.assert_allclose(got["state"], ref["state"], rtol=1e-9, atol=1e-7)
        np.testing.assert_allclose(got["cov"], ref["cov"], rtol=1e-7, atol=1e-12)
        np.testing.assert_array_equal(got["n_used"], ref["n_used"])
        np.testing.assert_allclose(got["mu"], 1.0)
    assert ref["n_used"][50] == 2  # the gate did reject the outlier


def test_imm_two_identical_models_equal_ekf():
    """Two identical models: the mixture collapses to the single filter whatever Π."""
    rng = np.random.default_rng(12)
    x, _ = _truth([(15.0, 0.3)])
    xy, aod, toa = _measure(x, rng, np.arange(0.0, 5000.0, 500.0))
    s0, p0 = _s0(x)
    cfg = _cfg(1.0)
    ref = run_ekf(_select(xy, aod, toa), DT, DH, cfg, s0, p0, len(xy))
    got = run_imm(_select(xy, aod, toa), DT, DH, cfg, ImmConfig((1.0, 1.0), (5.0, 1.0)), s0, p0, len(xy))
    np.testing.assert_allclose(got["state"], ref["state"], rtol=1e-9, atol=1e-7)
    np.testing.assert_allclose(got["mu"], np.tile(stationary(markov_matrix([5.0, 1.0], DT)), (len(xy), 1)), atol=1e-9)


def _lag_case(seed: int, gate: bool):
    """Acceleration step +1 -> -1.5 m/s² at 30 s; returns truth, change epoch, EKF and IMM runs
    (the EKF with the quiet model's q alone)."""
    rng = np.random.default_rng(seed)
    x, a = _truth([(30.0, 1.0), (30.0, -1.5)])
    xy, aod, toa = _measure(x, rng, np.arange(0.0, 8000.0, 500.0))
    s0, p0 = _s0(x)
    s0[4] = 1.0
    q_low = 0.01
    ekf = run_ekf(_select(xy, aod, toa), DT, DH, _cfg(q_low, gate), s0, p0, len(xy))
    imm = run_imm(
        _select(xy, aod, toa),
        DT,
        DH,
        _cfg(q_low, gate),
        ImmConfig((q_low, q_for_jump(2.5, DT)), (100.0, 1.0)),
        s0,
        p0,
        len(xy),
    )
    return x, 300, ekf, imm


def test_imm_responds_faster_than_low_q_ekf_at_a_manoeuvre():
    """No gate: after a known acceleration step (Δa = −2.5 m/s²) the IMM's along-track lag
    over the next 5 s is well below that of the EKF with the quiet model's q alone, its
    manoeuvre model's probability rises, and in the quiet phase it is not much worse."""
    lag_e, lag_i, quiet_e, quiet_i, mu_after, mu_quiet = [], [], [], [], [], []
    for seed in range(3):
        x, c, ekf, imm = _lag_case(seed, gate=False)
        w, q = slice(c, c + 50), slice(100, 290)
        lag_e.append(np.mean(ekf["state"][w, 0] - x[w]))  # Δa < 0: a lagging filter overshoots (+)
        lag_i.append(np.mean(imm["state"][w, 0] - x[w]))
        quiet_e.append(np.mean(np.abs(ekf["state"][q, 0] - x[q])))
        quiet_i.append(np.mean(np.abs(imm["state"][q, 0] - x[q])))
        mu_after.append(imm["mu"][w, 1].mean())
        mu_quiet.append(imm["mu"][q, 1].mean())
    assert np.mean(lag_e) > 0.15  # the low-q EKF lags measurably (≈ 0.23 m here)
    assert np.mean(lag_i) < 0.5 * np.mean(lag_e)
    assert np.mean(mu_after) > 3 * np.mean(mu_quiet)
    assert np.mean(quiet_i) < 1.5 * np.mean(quiet_e)


def test_imm_keeps_the_track_the_gated_low_q_ekf_loses():
    """With the χ² gate and no re-acquisition, the low-q EKF's prediction leaves the gate
    after the step and it never updates again; the IMM's union gate lets the manoeuvre
    model see the measurements, so it keeps updating."""
    for seed in range(3):
        x, c, ekf, imm = _lag_case(seed, gate=True)
        assert np.all(ekf["n_used"][c + 30 :] == 0)
        assert np.all(imm["n_used"][c:] > 0)
        assert np.mean(np.abs(imm["state"][c:, 0] - x[c:])) < 0.5


def test_track_filters_ekf_is_tracks_ekf():
    """The EKF of ``track_filters`` (selection, initial fix, gate, re-acquisition restated)
    is exactly :func:`railradio.nr.tracking.track.track`'s on a dataset with a lost stretch."""
    rng = np.random.default_rng(5)
    x, a = _truth([(10.0, 0.5), (10.0, -0.5)], v0=0.0, x0=1200.0)
    rrh_x = np.arange(0.0, 5000.0, 500.0)
    n, n_cand = x.size, 6
    rrh = np.stack([np.sort(np.argsort(np.abs(rrh_x - xk))[:n_cand]) for xk in x])
    dx = x[:, None] - rrh_x[rrh]
    aod = np.arctan2(-RRH_Y, dx) + SIG_AOD * rng.standard_normal((n, n_cand))
    toa = np.sqrt(dx**2 + RRH_Y**2 + DH**2) / SPEED_OF_LIGHT_M_S + SIG_TOA * rng.standard_normal((n, n_cand))
    toa[60:90] += 50.0 / SPEED_OF_LIGHT_M_S  # all measurements far off: gated, track lost, re-acquired
    aod[:2] = np.nan  # the first epochs without detections
    peak = -np.abs(dx) + rng.standard_normal((n, n_cand))
    ds = xr.Dataset(
        {
            "rrh": (("epoch", "cand"), rrh),
            "aod_hat": (("epoch", "cand"), aod),
            "toa_hat": (("epoch", "cand"), toa),
            "peak": (("epoch", "cand"), peak),
        }
    )
    cfg = _cfg(0.1)
    ref = track(ds, rrh_x, RRH_Y, DH, DT, cfg, strength="peak", snapshot=False)
    got = track_filters(ds, rrh_x, RRH_Y, DH, DT, cfg, ImmConfig((0.1, 10.0), (100.0, 1.0)), strength="peak")
    assert got["k0"] == ref["k0"] == 2
    np.testing.assert_array_equal(got["ekf"]["state"], ref["state"])
    np.testing.assert_array_equal(got["ekf"]["reacquired"], ref["reacquired"])
    assert ref["reacquired"].any()
    assert np.all(np.isnan(got["imm"]["state"][:2])) and np.all(np.isfinite(got["imm"]["state"][2:]))
    assert got["imm"]["reacquired"].any()  # the IMM re-acquires by the same rule
    np.testing.assert_allclose(got["imm"]["mu"][2:].sum(axis=1), 1.0)
    err = np.hypot(got["imm"]["state"][100:, 0] - x[100:], got["imm"]["state"][100:, 1])
    assert np.mean(err) < 2.0  # back on track after the re-acquisition


# ---- the RTS smoother ----------------------------------------------------------------


def _linear_case(seed: int, n: int = 3000, q: float = 0.5, sigma_m: float = 1.0):
    """Truth drawn from the white-jerk model itself; linear position measurements."""
    rng = np.random.default_rng(seed)
    f, qm = transition(DT), process_noise(DT, q)
    lq = np.linalg.cholesky(qm + 1e-18 * np.eye(6))
    s = np.zeros((n, 6))
    s[0] = [0.0, 0.0, 50.0, 0.0, 0.0, 0.0]
    for k in range(1, n):
        s[k] = f @ s[k - 1] + lq @ rng.standard_normal(6)
    z = s[:, :2] + sigma_m * rng.standard_normal((n, 2))
    kf = KalmanFilter(dim_x=6, dim_z=2)
    kf.F, kf.Q, kf.R = f, qm, sigma_m**2 * np.eye(2)
    kf.H = np.hstack([np.eye(2), np.zeros((2, 4))])
    kf.x, kf.P = s[0].copy(), np.diag([1.0, 1.0, 1.0, 1.0, 1.0, 1.0]) * 1e-6
    xs, ps = np.zeros((n, 6)), np.zeros((n, 6, 6))
    for k in range(n):
        if k:
            kf.predict()
        kf.update(z[k])
        xs[k], ps[k] = kf.x, kf.P
    return s, xs, ps, kf, f, qm


def test_rts_matches_filterpy_and_beats_the_filter():
    s, xs, ps, kf, f, qm = _linear_case(3)
    x_s, p_s = rts_smooth(xs, ps, f, qm)
    ref_x, ref_p, _, _ = kf.rts_smoother(xs, ps)
    np.testing.assert_allclose(x_s, ref_x, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(p_s, ref_p, rtol=1e-7, atol=1e-12)
    e_f = np.hypot(*(xs[:, :2] - s[:, :2]).T)
    e_s = np.hypot(*(x_s[:, :2] - s[:, :2]).T)
    assert np.mean(e_s) < 0.85 * np.mean(e_f)
    # the smoothed covariance is the smaller one, epoch by epoch
    assert np.all(np.trace(p_s[:, :2, :2], axis1=1, axis2=2) <= np.trace(ps[:, :2, :2], axis1=1, axis2=2) + 1e-12)


def test_rts_and_filter_nees_consistent():
    """Truth from the model: the 2-D position NEES of filter and smoother average 2 (χ²₂)."""
    nf, ns = [], []
    for seed in range(4):
        s, xs, ps, _, f, qm = _linear_case(seed, n=2000)
        x_s, p_s = rts_smooth(xs, ps, f, qm)
        nf.append(position_nees(xs, ps, s[:, 0], s[:, 1])[100:])
        ns.append(position_nees(x_s, p_s, s[:, 0], s[:, 1])[100:])
    assert np.mean(np.concatenate(nf)) == pytest.approx(2.0, abs=0.25)
    assert np.mean(np.concatenate(ns)) == pytest.approx(2.0, abs=0.25)


def test_rts_keeps_leading_nan_epochs():
    s, xs, ps, _, f, qm = _linear_case(1, n=50)
    xs[:5] = np.nan
    ps[:5] = np.nan
    x_s, _ = rts_smooth(xs, ps, f, qm)
    assert np.all(np.isnan(x_s[:5])) and np.all(np.isfinite(x_s[5:]))
    xs[20] = np.nan
    with pytest.raises(ValueError, match="finite"):
        rts_smooth(xs, ps, f, qm)


# ---- key numbers ---------------------------------------------------------------------


def _report_ds(lag: float = 0.4, after_err: float = 1.0) -> xr.Dataset:
    n = 400
    t = np.arange(n) * DT
    pos = np.full((3, n), 0.2)
    along = np.zeros((3, n))
    pos[:, 200:300] = [[after_err], [after_err / 2], [after_err / 4]]
    along[:, 200:300] = [[lag], [lag / 2], [0.0]]
    mu = np.full((2, n), 0.0)
    mu[0], mu[1] = 0.99, 0.01
    mu[1, 200:300] = 0.3
    return xr.Dataset(
        {
            "pos_err": (("filter", "epoch"), pos),
            "along_err": (("filter", "epoch"), along),
            "pos_nees": (("filter", "epoch"), np.full((3, n), 2.0)),
            "mode_prob": (("mode", "epoch"), mu),
            "t": (("epoch",), t),
            "q": (("mode",), [0.01, 10.0]),
            "change_epoch": (("change",), [200]),
            "delta_a": (("change",), [-0.85]),
        },
        coords={"filter": ["ekf", "imm", "rts"], "mode": ["quiet", "manoeuvre"]},
        attrs={"config_json": json.dumps({"sim": {"deployment": {"spacing_m": 500.0}}})},
    )


def test_key_numbers_measure_the_lag():
    k = key_numbers([_report_ds(), _report_ds()], window_s=10.0)
    assert k["nr.track.ekf.lag_m.after_change_mean"]["value"] == pytest.approx(0.4)  # Δa < 0, x̂ ahead: +
    assert k["nr.track.imm.lag_m.after_change_mean"]["value"] == pytest.approx(0.2)
    assert k["nr.track.rts.lag_m.after_change_mean"]["value"] == pytest.approx(0.0)
    assert k["nr.track.ekf.err_m.after_change_mean"]["value"] == pytest.approx(1.0)
    assert k["nr.track.imm.err_m.after_change_mean"]["value"] == pytest.approx(0.5)
    assert k["nr.track.imm.manoeuvre_prob.after_change_mean"]["value"] == pytest.approx(0.3)
    assert k["nr.track.ekf.err_m.mean"]["mc_stderr"] == pytest.approx(0.0)
    assert k["nr.track.imm.q_manoeuvre"]["value"] == 10.0 and k["nr.track.imm.q_quiet"]["mc_stderr"] is None
    skip = np.arange(400) * DT >= 5.0
    expect = np.mean(np.where(np.arange(400) >= 200, np.where(np.arange(400) < 300, 1.0, 0.2), 0.2)[skip])
    assert k["nr.track.ekf.err_m.mean"]["value"] == pytest.approx(expect)
    for name in (
        "nr.track.imm.err_m.mean",
        "nr.track.imm.err_m.p95",
        "nr.track.rts.err_m.mean",
        "nr.track.ekf.err_m.after_change_mean",
        "nr.track.imm.err_m.after_change_mean",
        "nr.track.rts.err_m.after_change_mean",
    ):
        assert k[name]["value"] is not None


def test_key_numbers_without_changes_are_null():
    ds = _report_ds().isel(change=slice(0, 0))
    k = key_numbers([ds], window_s=10.0)
    assert k["nr.track.imm.err_m.after_change_mean"]["value"] is None
    assert k["nr.track.imm.err_m.mean"]["value"] is not None
    with pytest.raises(ValueError, match="runs"):
        key_numbers([], window_s=10.0)
