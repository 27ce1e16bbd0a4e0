"""TDOA/AOA ∩ track: closed form against brute-force root finding and exact geometry."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from railradio.fusion import (
    CellGeometry,
    aoa_on_track,
    aoa_variance_propagated,
    clip_to_segment,
    fuse,
    tdoa_on_track,
    tdoa_on_track_rootfind,
    tdoa_variance_propagated,
)

geoms = st.builds(CellGeometry, d_m=st.floats(1.0, 5000.0), cell_radius_factor=st.floats(1.05, 10.0))


def _r2_minus_r1(x, g):  # independent of CellGeometry's own formulas
    return math.hypot(g.baseline_m - x, g.d_m) - math.hypot(x, g.d_m)


@settings(max_examples=300, deadline=None)
@given(g=geoms, frac=st.floats(-0.999, 0.999))
def test_closed_form_matches_root_finding(g, frac):
    delta = frac * g.baseline_m
    x_closed, nosol = tdoa_on_track(delta, g)
    assert not nosol
    x_ref = tdoa_on_track_rootfind(delta, g)
    # both solve r2 - r1 = delta; compare in position, with a tolerance scaled by how
    # flat the hyperbola is there (|dx/dΔ| = 1/|g|)
    tol = 1e-7 * g.baseline_m / abs(float(g.range_difference_slope(x_ref)))
    assert abs(float(x_closed) - x_ref) <= tol
    assert abs(_r2_minus_r1(float(x_closed), g) - delta) <= 1e-6 * g.baseline_m


@settings(max_examples=200, deadline=None)
@given(g=geoms, u=st.floats(-3.0, 3.0))
def test_noiseless_measurements_give_exact_position(g, u):
    x = u * g.half_segment_m
    x_t, _ = tdoa_on_track(_r2_minus_r1(x, g), g)
    assert float(x_t) == pytest.approx(x, abs=1e-6 * g.baseline_m)
    theta = math.atan2(-g.d_m, x)
    assert float(aoa_on_track(theta, g)) == pytest.approx(x, abs=1e-9 * max(g.d_m, abs(x)))


def test_no_solution_is_flagged_and_clipped_to_the_nearer_end():
    g = CellGeometry(100.0)
    delta = np.array([g.baseline_m, 1.5 * g.baseline_m, -g.baseline_m, 0.0])
    x, nosol = tdoa_on_track(delta, g)
    np.testing.assert_array_equal(nosol, [True, True, True, False])
    assert np.isneginf(x[0]) and np.isposinf(x[2])
    xc, clipped = clip_to_segment(x, g)
    lo, hi = g.segment_m
    np.testing.assert_allclose(xc, [lo, lo, hi, g.baseline_m / 2])
    np.testing.assert_array_equal(clipped, [True, True, True, False])
    assert tdoa_on_track_rootfind(1.2 * g.baseline_m, g) == -np.inf


def test_source_geometry():
    g = CellGeometry(1500.0)
    assert g.baseline_m == pytest.approx(2 * math.sqrt(3) * 1500)
    assert g.train_interval_m == pytest.approx((0.0, math.sqrt(3) * 1500))


@pytest.mark.parametrize(
    "bad", [dict(d_m=0.0), dict(d_m=-1.0), dict(d_m=10.0, cell_radius_factor=1.0), dict(d_m=float("nan"))]
)
def test_bad_geometry_raises(bad):
    with pytest.raises(ValueError):
        CellGeometry(**bad)


def test_fuse_inverse_variance():
    assert float(fuse(0.0, 1.0, 10.0, 4.0)) == pytest.approx(2.0)
    with pytest.raises(ValueError, match="var_a"):
        fuse(0.0, 0.0, 1.0, 1.0)


def test_propagated_variances_match_small_noise_monte_carlo(rng):
    g = CellGeometry(1500.0)
    x0, n = 1000.0, 200_000
    s_delta, s_theta = 1.0, 1e-4  # linear regime
    x_t, _ = tdoa_on_track(g.range_difference_m(x0) + s_delta * rng.standard_normal(n), g)
    x_a = aoa_on_track(g.aoa_rad(x0) + s_theta * rng.standard_normal(n), g)
    # sample variances of n draws are within ~4*sqrt(2/n) = 1.3 % of the truth
    assert np.var(x_t) == pytest.approx(float(tdoa_variance_propagated(x0, s_delta, g)), rel=0.015)
    assert np.var(x_a) == pytest.approx(float(aoa_variance_propagated(x0, s_theta, g)), rel=0.015)
