"""Fusion sensitivity (docs/model/fusion.md §5): the arc geometry and its estimators against independent
geometry and root finding, the correlated-noise generator, the CRLBs against numerical
Fisher information, whitening at ρ = 0, Monte Carlo against the bounds, bad input."""

import math
import re

import numpy as np
import pytest
from scipy.optimize import brentq

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.fusion import CellGeometry, PointParams, aoa_on_track, fisher_information, fuse, tdoa_on_track
from railradio.fusion.arc import (
    ArcGeometry,
    aoa_on_arc,
    fisher_information_arc,
    line_range_difference_slope,
    tdoa_on_arc,
    tdoa_on_line,
)
from railradio.fusion.correlated import (
    common_reference_rho,
    correlated_pair,
    fisher_information_correlated,
    fuse_two_tdoa_aoa,
    range_difference0_m,
    range_difference0_slope,
    tdoa0_on_track,
)
from railradio.fusion.sensitivity import (
    SensPoint,
    point_key,
    sens_points,
    sens_sweep_dataset,
    simulate_sens_point,
    summarize_sens,
)
from railradio.fusion.sensitivity_keys import key_numbers

SIGMA_DELTA_M = SPEED_OF_LIGHT_M_S * 1e-7  # the source's 0.1 µs
SIGMA_THETA_RAD = 0.01
RADII = [1e7, 20000.0, 7000.0, 4000.0, 2000.0]


# --- independent arc geometry: centre-angle form, written out here -------------------
def _arc_indep(s, d, radius):
    """Track point and BS1/BS2 on circles about (0, R) by their centre angles."""
    big_d = 2 * math.sqrt(3) * d
    phi = s / radius
    p = np.array([radius * math.sin(phi), radius - radius * math.cos(phi)])
    bs = [np.array([(radius - d) * math.sin(a), radius - (radius - d) * math.cos(a)]) for a in (0.0, big_d / radius)]
    return p, bs


def _mu(s, d, radius):
    """(r2 - r1, bearing at BS1) from the independent geometry."""
    p, (b1, b2) = _arc_indep(s, d, radius)
    return np.array([np.linalg.norm(p - b2) - np.linalg.norm(p - b1), math.atan2(*(p - b1)[::-1])])


@pytest.mark.parametrize("radius", [20000.0, 4000.0, 2000.0])
@pytest.mark.parametrize("u", [-0.8, 0.0, 0.4, 1.0])
def test_arc_geometry_matches_centre_angle_form(radius, u):
    g = ArcGeometry(1500.0, radius)
    s = u * g.half_segment_m
    p, (b1, b2) = _arc_indep(s, 1500.0, radius)
    np.testing.assert_allclose(np.array(g.track_xy_m(s), dtype=float), p, atol=1e-8)
    np.testing.assert_allclose(g.bs_xy_m[0], b1, atol=1e-8)
    np.testing.assert_allclose(g.bs_xy_m[1], b2, atol=1e-8)
    # each BS is d from the track's point at its foot, along the normal
    for s_k, b in ((0.0, b1), (g.baseline_m, b2)):
        assert np.linalg.norm(np.array(g.track_xy_m(s_k), dtype=float) - b) == pytest.approx(1500.0)
    assert float(g.range_difference_m(s)) == pytest.approx(_mu(s, 1500.0, radius)[0], abs=1e-7)
    assert float(g.aoa_rad(s)) == pytest.approx(_mu(s, 1500.0, radius)[1], abs=1e-12)
    assert float(g.sagitta_m(s)) == pytest.approx(radius * (1 - math.cos(s / radius)), rel=1e-9, abs=1e-9)


def test_straight_arc_is_the_source_geometry():
    g, c = ArcGeometry(1500.0), CellGeometry(1500.0)
    x = np.linspace(-c.half_segment_m, c.half_segment_m, 11)
    assert g.bs_xy_m == ((0.0, 1500.0), (c.baseline_m, 1500.0))
    np.testing.assert_allclose(g.range_difference_m(x), c.range_difference_m(x), rtol=1e-14)
    np.testing.assert_allclose(g.range_difference_slope(x), c.range_difference_slope(x), rtol=1e-14)
    np.testing.assert_allclose(g.aoa_slope(x), c.aoa_slope(x), rtol=1e-14)
    np.testing.assert_allclose(
        fisher_information_arc(x, SIGMA_DELTA_M, SIGMA_THETA_RAD, g),
        fisher_information(x, SIGMA_DELTA_M, SIGMA_THETA_RAD, c),
        rtol=1e-13,
    )
    assert g.tdoa_branch_m == (-math.inf, math.inf)


@pytest.mark.parametrize("radius", RADII)
@pytest.mark.parametrize("u", [-0.9, 0.0, 0.5, 1.0])
def test_arc_fisher_matches_numerical_fisher_information(radius, u):
    """J(s) closed form vs mu'(s)^T Sigma^-1 mu'(s), mu' by central differences of the
    independent centre-angle geometry."""
    g = ArcGeometry(1500.0, radius)
    s, h = u * g.half_segment_m, 1e-3
    dmu = (_mu(s + h, 1500.0, radius) - _mu(s - h, 1500.0, radius)) / (2 * h)
    j_num = dmu @ np.linalg.inv(np.diag([SIGMA_DELTA_M**2, SIGMA_THETA_RAD**2])) @ dmu
    assert float(fisher_information_arc(s, SIGMA_DELTA_M, SIGMA_THETA_RAD, g)) == pytest.approx(j_num, rel=1e-6)


@pytest.mark.parametrize("radius", RADII)
def test_tdoa_on_arc_matches_root_finding_and_is_exact_without_noise(radius, rng):
    g = ArcGeometry(1500.0, radius)
    s_a, s_b = g.tdoa_branch_m
    # the branch: Δ decreasing on (s_a, s_b), flat at its ends
    grid = np.linspace(s_a, s_b, 2001)
    assert np.all(np.diff(g.range_difference_m(grid)) < 0)
    assert abs(float(g.range_difference_slope(s_a))) < 1e-9
    # on a tight curve the branch starts inside the segment (R = 4 km: s_a = -1.1 km):
    # behind it the range difference is ambiguous, and the estimator keeps to the branch
    s_true = rng.uniform(max(-g.half_segment_m, s_a + 1.0), g.half_segment_m, 40)
    s_hat, nosol = tdoa_on_arc(g.range_difference_m(s_true), g)
    assert not nosol.any()
    np.testing.assert_allclose(s_hat, s_true, atol=1e-6)
    deltas = g.range_difference_m(s_true) + 30.0 * rng.standard_normal(40)
    s_hat, nosol = tdoa_on_arc(deltas, g)
    for dl, sh, ns in zip(deltas, s_hat, nosol, strict=True):
        if ns:
            continue
        ref = brentq(lambda s, dl=dl: _mu(s, 1500.0, radius)[0] - dl, s_a, s_b, xtol=1e-10)
        assert sh == pytest.approx(ref, abs=1e-6)


def test_tdoa_on_arc_without_solution_takes_the_branch_end():
    g = ArcGeometry(1500.0, 2000.0)
    s_a, s_b = g.tdoa_branch_m
    top = float(g.range_difference_m(s_a))
    s, nosol = tdoa_on_arc(np.array([top + 1.0, -top - 1.0, 0.0]), g)
    np.testing.assert_array_equal(nosol, [True, True, False])
    assert s[0] == s_a and s[1] == s_b and s[2] == pytest.approx(0.5 * g.baseline_m)


def test_tdoa_on_arc_tends_to_the_straight_closed_form(rng):
    c = CellGeometry(1500.0)
    deltas = c.range_difference_m(rng.uniform(0, c.half_segment_m, 50)) + 30 * rng.standard_normal(50)
    for radius in (1e9, 1e12):  # the curvature's effect is of the order of the sagitta
        g = ArcGeometry(1500.0, radius)
        s_big_r, _ = tdoa_on_arc(deltas, g)
        np.testing.assert_allclose(
            s_big_r, tdoa_on_track(deltas, c)[0], atol=1e-6 + 2 * float(g.sagitta_m(g.half_segment_m))
        )


@pytest.mark.parametrize("radius", RADII)
def test_aoa_on_arc_exact_and_unique(radius, rng):
    g = ArcGeometry(1500.0, radius)
    s_true = rng.uniform(-g.half_segment_m, g.half_segment_m, 30)
    np.testing.assert_allclose(aoa_on_arc(g.aoa_rad(s_true), g), s_true, atol=1e-6)
    # brute force: the bearing along the arc crosses theta once (BS1 inside the circle)
    theta = g.aoa_rad(0.7 * g.half_segment_m) + 0.02
    s = (
        np.linspace(-math.pi * radius + 1.0, math.pi * radius - 1.0, 200001)
        if radius < 1e6
        else np.linspace(-1e5, 1e5, 200001)
    )
    f = np.angle(np.exp(1j * (g.aoa_rad(s) - theta)))
    crossings = np.flatnonzero((np.sign(f[:-1]) != np.sign(f[1:])) & (np.abs(f[:-1] - f[1:]) < 1.0))
    assert len(crossings) == 1
    assert float(aoa_on_arc(theta, g)) == pytest.approx(s[crossings[0]], abs=2 * (s[1] - s[0]))


def test_aoa_on_arc_straight_is_the_source():
    c = CellGeometry(1500.0)
    theta = np.array([-0.3, -0.7, -1.5])
    np.testing.assert_array_equal(aoa_on_arc(theta, ArcGeometry(1500.0)), aoa_on_track(theta, c))


@pytest.mark.parametrize("radius", [20000.0, 7000.0, 4000.0])
def test_mismatch_line_estimator_matches_root_finding(radius, rng):
    """The source's straight-line TDOA with the true (curved-layout) BS2 coordinates."""
    g = ArcGeometry(1500.0, radius)
    bs2 = g.bs_xy_m[1]

    def r2_minus_r1(x):
        return math.hypot(x - bs2[0], bs2[1]) - math.hypot(x, 1500.0)

    # y2 > d: r2 - r1 on the line peaks behind BS1 (at x_m) above its limit x2
    grid = np.linspace(-50_000.0, 0.0, 500_001)
    values = np.array([r2_minus_r1(x) for x in grid[::100]])
    x_m = grid[::100][np.argmax(values)]
    assert bs2[1] > 1500.0 and values.max() > bs2[0]
    for x in rng.uniform(max(-2600.0, x_m + 50.0), 2600.0, 20):
        x_hat, nosol = tdoa_on_line(r2_minus_r1(x), 1500.0, bs2)
        assert not nosol and float(x_hat) == pytest.approx(x, abs=1e-6)
        h = 1e-3
        fd = (r2_minus_r1(x + h) - r2_minus_r1(x - h)) / (2 * h)
        assert float(line_range_difference_slope(x, 1500.0, bs2)) == pytest.approx(fd, rel=1e-6)
    # above the peak: no solution (-inf, clipped like the source's); behind it: the cell's branch
    assert bool(tdoa_on_line(values.max() + 1.0, 1500.0, bs2)[1])
    x_behind = x_m - 3000.0
    x_hat, nosol = tdoa_on_line(r2_minus_r1(x_behind), 1500.0, bs2)
    assert not nosol and float(x_hat) > x_m and r2_minus_r1(float(x_hat)) == pytest.approx(r2_minus_r1(x_behind))


def test_line_estimator_is_the_source_closed_form_on_the_straight_layout(rng):
    c = CellGeometry(1500.0)
    deltas = rng.uniform(-0.99, 0.99, 100) * c.baseline_m
    np.testing.assert_allclose(
        tdoa_on_line(deltas, 1500.0, (c.baseline_m, 1500.0))[0], tdoa_on_track(deltas, c)[0], rtol=1e-9, atol=1e-7
    )


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        (dict(d_m=1500.0, radius_m=1500.0), "radius_m"),
        (dict(d_m=1500.0, radius_m=1600.0), "radius_m"),  # D/R > pi
        (dict(d_m=1500.0, radius_m=-5.0), "radius_m"),
        (dict(d_m=1500.0, radius_m=float("nan")), "radius_m"),
        (dict(d_m=0.0, radius_m=5000.0), "d_m"),
    ],
)
def test_bad_arc_geometry_raises_naming_the_parameter(kwargs, name):
    with pytest.raises(ValueError, match=name):
        ArcGeometry(**kwargs)


def test_bad_estimator_input_raises_naming_the_parameter():
    g = ArcGeometry(1500.0, 4000.0)
    with pytest.raises(ValueError, match="sigma_delta_m"):
        fisher_information_arc(0.0, 0.0, 0.01, g)
    with pytest.raises(ValueError, match="bs2_xy_m"):
        tdoa_on_line(0.0, 1500.0, (-10.0, 1500.0))
    with pytest.raises(ValueError, match="tol_m"):
        tdoa_on_arc(0.0, g, tol_m=0.0)


# --- correlated TDOA errors --------------------------------------------------------
@pytest.mark.parametrize("rho", [0.0, 0.5, 0.9])
def test_correlated_pair_has_the_requested_covariance(rho, rng):
    n = 400_000
    a, b = correlated_pair(rng.standard_normal(n), rng.standard_normal(n), rho)
    cov = np.cov(a, b)
    # sample (co)variances of n draws: standard error <= sqrt(2/n) = 0.0022
    np.testing.assert_allclose(cov, [[1, rho], [rho, 1]], atol=0.01)


def test_common_reference_error_gives_rho_one_half(rng):
    """TDOAs from independent per-BS TOA errors with a common reference: ρ = 0.5."""
    n, sigma = 400_000, 1.0
    e0, e1, e2 = sigma * rng.standard_normal((3, n))
    c = np.corrcoef(e2 - e1, e0 - e1)
    assert c[0, 1] == pytest.approx(0.5, abs=0.01)
    assert common_reference_rho(sigma, sigma) == pytest.approx((0.5, math.sqrt(2) * sigma))
    assert common_reference_rho(3.0, 1.0)[0] == pytest.approx(0.9)


def test_third_bs_is_the_mirror_image():
    c = CellGeometry(1500.0)
    x = np.linspace(-2000.0, 2600.0, 9)
    r0 = np.hypot(x + c.baseline_m, 1500.0)
    r1 = np.hypot(x, 1500.0)
    np.testing.assert_allclose(range_difference0_m(x, c), r0 - r1, rtol=1e-12)
    h = 1e-3
    fd = (range_difference0_m(x + h, c) - range_difference0_m(x - h, c)) / (2 * h)
    np.testing.assert_allclose(range_difference0_slope(x, c), fd, rtol=1e-6)
    np.testing.assert_allclose(tdoa0_on_track(r0 - r1, c)[0], x, atol=1e-6)


@pytest.mark.parametrize("rho", [0.0, 0.3, 0.5, 0.9, -0.4])
@pytest.mark.parametrize("u", [0.0, 0.5, 1.0])
def test_correlated_crlb_matches_numerical_fisher_information(rho, u):
    c = CellGeometry(1500.0)
    x, h = u * c.half_segment_m, 1e-3

    def mu(x):  # (r2 - r1, r0 - r1, theta), written out
        big_d = c.baseline_m
        r0, r1, r2 = (math.hypot(x - xb, 1500.0) for xb in (-big_d, 0.0, big_d))
        return np.array([r2 - r1, r0 - r1, math.atan2(-1500.0, x)])

    dmu = (mu(x + h) - mu(x - h)) / (2 * h)
    cov = np.zeros((3, 3))
    cov[:2, :2] = SIGMA_DELTA_M**2 * np.array([[1, rho], [rho, 1]])
    cov[2, 2] = SIGMA_THETA_RAD**2
    j_num = dmu @ np.linalg.inv(cov) @ dmu
    j = float(fisher_information_correlated(x, SIGMA_DELTA_M, SIGMA_THETA_RAD, rho, c))
    assert j == pytest.approx(j_num, rel=1e-6)


def test_whitened_fusion_is_gls_and_reduces_to_the_source_at_rho_zero(rng):
    x = rng.normal(1000.0, 20.0, (3, 50))
    sd2, sd0 = -rng.uniform(10, 30, 50), rng.uniform(10, 30, 50)
    var_a = rng.uniform(100, 1000, 50)
    for rho in (0.0, 0.5, 0.9):
        got = fuse_two_tdoa_aoa(x[0], sd2, x[1], sd0, x[2], var_a, rho)
        for k in range(50):  # reference: generalized least squares with numpy.linalg
            cov = np.diag([sd2[k] ** 2, sd0[k] ** 2, var_a[k]])
            cov[0, 1] = cov[1, 0] = rho * sd2[k] * sd0[k]
            w = np.linalg.solve(cov, np.ones(3))
            assert got[k] == pytest.approx(w @ x[:, k] / w.sum(), rel=1e-12)
    # rho = 0: inverse-variance weighting of three independent estimates
    w = np.array([1 / sd2**2, 1 / sd0**2, 1 / var_a])
    np.testing.assert_allclose(
        fuse_two_tdoa_aoa(x[0], sd2, x[1], sd0, x[2], var_a, 0.0), (w * x).sum(0) / w.sum(0), rtol=1e-13
    )
    # one TDOA (the second dropped): the source's two-estimate fusion (eq. 9-10)
    np.testing.assert_allclose(
        fuse_two_tdoa_aoa(x[0], sd2, np.inf, np.inf, x[2], var_a, 0.0), fuse(x[0], sd2**2, x[2], var_a), rtol=1e-13
    )


@pytest.mark.parametrize("rho", [1.0, -1.0, float("nan")])
def test_bad_rho_raises_naming_it(rho):
    with pytest.raises(ValueError, match="rho"):
        correlated_pair([0.0], [0.0], rho)
    with pytest.raises(ValueError, match="rho"):
        fisher_information_correlated(0.0, 1.0, 0.01, rho, CellGeometry(1500.0))
    with pytest.raises(ValueError, match="rho"):
        SensPoint(PointParams(1500.0, 1e-7, 0.01, 10, 10), "rho", rho=rho)


def test_bad_fusion_input_raises_naming_it():
    with pytest.raises(ValueError, match="sd_t0"):
        fuse_two_tdoa_aoa(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.5)
    with pytest.raises(ValueError, match="var_a"):
        fuse_two_tdoa_aoa(0.0, 1.0, 0.0, 1.0, 0.0, -1.0, 0.5)
    with pytest.raises(ValueError, match="sigma_ref_s"):
        common_reference_rho(-1.0, 1.0)


# --- Monte Carlo -------------------------------------------------------------------
def _point(kind, n_pos=60, n_trials=2000, **kw):
    return SensPoint(PointParams(1500.0, 1e-7, 0.01, n_positions=n_pos, n_trials=n_trials), kind, **kw)


def test_whitened_equals_naive_at_rho_zero_in_the_monte_carlo():
    ds = simulate_sens_point(_point("rho", 10, 200, rho=0.0), 1, (2, 3))
    np.testing.assert_array_equal(ds["mse"].sel(estimator="whitened").values, ds["mse"].sel(estimator="naive").values)


@pytest.mark.parametrize("rho", [0.0, 0.5, 0.9])
def test_whitened_sits_on_the_correlated_crlb_and_naive_on_its_prediction(rho):
    p = _point("rho", 60, 3000, rho=rho)
    ds = simulate_sens_point(p, 7, (2, 11))
    s = summarize_sens(ds)
    # nonlinearity allowance: 1 % at rho <= 0.5, 3 % at 0.9 (the bound shrinks, the
    # second-order terms of the clipped closed forms do not)
    allow = 0.01 if rho <= 0.5 else 0.03
    assert abs(s["rmse_whitened_m"] - s["crlb_m"]) <= 4 * s["rmse_whitened_se_m"] + allow * s["crlb_m"]
    # naive: its linearized variance w^T C w with the independent weights
    g = CellGeometry(1500.0)
    x = ds["x_true"].values
    v2 = (SIGMA_DELTA_M / g.range_difference_slope(x)) ** 2
    v0 = (SIGMA_DELTA_M / range_difference0_slope(x, g)) ** 2
    va = (SIGMA_THETA_RAD / g.aoa_slope(x)) ** 2
    c = rho * SIGMA_DELTA_M**2 / (g.range_difference_slope(x) * range_difference0_slope(x, g))
    w = np.array([1 / v2, 1 / v0, 1 / va]) / (1 / v2 + 1 / v0 + 1 / va)
    var = w[0] ** 2 * v2 + w[1] ** 2 * v0 + w[2] ** 2 * va + 2 * w[0] * w[1] * c
    pred = float(np.sqrt(var.mean()))
    assert abs(s["rmse_naive_m"] - pred) <= 4 * s["rmse_naive_se_m"] + 0.01 * pred
    if rho > 0:
        assert s["rmse_whitened_m"] < s["rmse_naive_m"]


def test_curve_straight_base_equal_for_both_constraints_and_arc_on_its_crlb():
    base = simulate_sens_point(_point("curve"), 3, (2, 5))
    np.testing.assert_allclose(
        base["mse"].sel(estimator="mismatch_fused").values, base["mse"].sel(estimator="arc_fused").values, rtol=1e-9
    )
    prev_bias = 0.0
    for radius in (20000.0, 7000.0, 4000.0):
        s = summarize_sens(simulate_sens_point(_point("curve", radius_m=radius), 3, (2, 5)))
        assert abs(s["rmse_arc_fused_m"] - s["crlb_m"]) <= 4 * s["rmse_arc_fused_se_m"] + 0.01 * s["crlb_m"]
        # the straight-line constraint is biased, more so the tighter the curve
        assert s["bias_rms_mismatch_fused_m"] > prev_bias
        assert s["rmse_mismatch_fused_m"] > s["rmse_arc_fused_m"] + 4 * s["rmse_mismatch_fused_se_m"]
        prev_bias = s["bias_rms_mismatch_fused_m"]


def test_results_do_not_depend_on_chunking_and_use_common_random_numbers():
    p = _point("curve", 13, 100, radius_m=7000.0)
    a = simulate_sens_point(p, 3, (2, 1), chunk_positions=4)
    b = simulate_sens_point(p, 3, (2, 1), chunk_positions=50)
    np.testing.assert_array_equal(a["mse"].values, b["mse"].values)
    cfg = {
        "reference": {"d_m": 1500.0, "sigma_tdoa_us": 0.1, "sigma_aoa_rad": 0.01},
        "position_sampling": "grid",
        "cell_radius_factor": 2.0,
        "clip": "no_solution",
        "sensitivity": {"n_positions": 5, "n_trials": 50, "radii_m": [4000.0, 2000.0], "rho": [0.0, 0.5]},
    }
    for kind in ("curve", "rho"):
        keys = {point_key(pt) for pt in sens_points(cfg, kind)}
        assert len(keys) == 1  # the same random numbers at every point of a sweep
    assert point_key(sens_points(cfg, "curve")[0]) != point_key(sens_points(cfg, "rho")[0])


def test_sens_points_reject_a_radius_the_layout_cannot_take():
    cfg = {
        "reference": {"d_m": 1500.0, "sigma_tdoa_us": 0.1, "sigma_aoa_rad": 0.01},
        "position_sampling": "grid",
        "cell_radius_factor": 2.0,
        "clip": "no_solution",
        "sensitivity": {"n_positions": 5, "n_trials": 50, "radii_m": [1000.0], "rho": [0.5]},
    }
    with pytest.raises(ValueError, match="radius_m"):
        sens_points(cfg, "curve")
    with pytest.raises(ValueError, match="kind"):
        sens_points(cfg, "bend")


def test_key_numbers_names_and_values():
    curve = sens_sweep_dataset(
        [simulate_sens_point(_point("curve", 8, 50, radius_m=r), 1, (2, 9)) for r in (math.inf, 4000.0)], "curve"
    )
    rho = sens_sweep_dataset([simulate_sens_point(_point("rho", 8, 50, rho=r), 1, (2, 9)) for r in (0.0, 0.5)], "rho")
    nums = key_numbers(curve, rho)
    for name in (
        "sens.fusion.curve_r4000.mismatch.rmse_m",
        "sens.fusion.curve_r4000.arc.rmse_m",
        "sens.fusion.curve_rinf.crlb_m",
        "sens.fusion.curve_r4000.sagitta_m",
        "sens.fusion.rho0.5.naive.rmse_m",
        "sens.fusion.rho0.5.whitened.rmse_m",
        "sens.fusion.rho0.5.crlb_m",
        "sens.fusion.rho0.crlb_m",
        "sens.fusion.one_tdoa.rmse_m",
    ):
        assert name in nums, name
    assert nums["sens.fusion.curve_rinf.sagitta_m"]["value"] == 0.0
    g = ArcGeometry(1500.0, 4000.0)
    assert nums["sens.fusion.curve_r4000.sagitta_m"]["value"] == pytest.approx(
        4000.0 * (1 - math.cos(g.half_segment_m / 4000.0))
    )
    assert all(e["value"] is not None and math.isfinite(e["value"]) for e in nums.values())


@pytest.mark.parametrize(
    ("key", "bad", "text"),
    [
        ("rho", [0.5, 1.0], "fusion.sensitivity.rho[1]"),
        ("radii_m", [50.0], "fusion.sensitivity.radii_m[0]"),
        ("n_trials", 1, "fusion.sensitivity.n_trials"),
        ("radii", [4000.0], "radii"),
    ],
)
def test_schema_rejects_bad_sensitivity_config_naming_the_key(key, bad, text):
    import copy

    import yaml

    from railradio.config import ConfigError, load_schema, validate_config
    from tests.conftest import ROOT

    schema = load_schema(ROOT / "workflow/schemas/config.schema.yaml")
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    validate_config(copy.deepcopy(cfg), schema)
    cfg["fusion"]["sensitivity"][key] = bad
    with pytest.raises(ConfigError, match=re.escape(text)):
        validate_config(cfg, schema)


def test_sensitivity_figure_is_written(tmp_path):
    from railradio.fusion.sensitivity_figures import plot_sensitivity

    curve = sens_sweep_dataset(
        [simulate_sens_point(_point("curve", 6, 30, radius_m=r), 1, (2, 4)) for r in (math.inf, 7000.0)], "curve"
    )
    rho = sens_sweep_dataset([simulate_sens_point(_point("rho", 6, 30, rho=r), 1, (2, 4)) for r in (0.0, 0.9)], "rho")
    plot_sensitivity(curve, rho, tmp_path / "f.pdf", tmp_path / "f.png")
    assert (tmp_path / "f.pdf").stat().st_size > 1000 and (tmp_path / "f.png").stat().st_size > 1000
    with pytest.raises(ValueError, match="curve"):
        plot_sensitivity(rho, curve, tmp_path / "g.pdf")
