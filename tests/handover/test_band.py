"""Band edges PL/PR, the inverse gap map, the fit and WSLR against closed forms."""

import numpy as np
import pytest
from scipy.optimize import brentq

from railradio.handover.band import (
    band_edges_m,
    fit_from_sums,
    gap_threshold_db,
    geometric_weights,
    inverse_gap_m,
    log_ratio,
    model_gap_db,
    position_correction_m,
    wslr_predict,
)
from railradio.handover.params import Joint, Radio

RADIO = Radio()


@pytest.mark.parametrize("a_db", [-4.0, 0.0, 2.5])
@pytest.mark.parametrize("n_hat", [2.0, 3.5, 6.0])
@pytest.mark.parametrize("gaph", [1.0, 6.56])
def test_band_edges_are_the_roots_of_the_gap_threshold(a_db, n_hat, gaph):
    pl, pr = band_edges_m(gaph, a_db, n_hat, RADIO)
    L = RADIO.spacing_m

    def g(x):
        return float(model_gap_db(x, a_db, n_hat, RADIO))

    pl_root = brentq(lambda x: g(x) - gaph, 1e-6, L - 1e-6, xtol=1e-10)
    pr_root = brentq(lambda x: g(x) + gaph, 1e-6, L - 1e-6, xtol=1e-10)
    assert pl == pytest.approx(pl_root, abs=1e-7)
    assert pr == pytest.approx(pr_root, abs=1e-7)
    # inside the band |G| <= GapH, just outside it is larger
    assert abs(g(0.5 * (pl + pr))) <= gaph
    assert g(pl - 1.0) > gaph and g(pr + 1.0) < -gaph


def test_band_is_symmetric_without_offset_and_widens_with_gaph():
    L = RADIO.spacing_m
    q = 10 ** (6.0 / 35.0)
    pl, pr = band_edges_m(6.0, 0.0, 3.5, RADIO)
    assert pl == pytest.approx(L / (1 + q)) and pr == pytest.approx(L * q / (1 + q))
    assert 0.5 * (pl + pr) == pytest.approx(L / 2)
    pl2, pr2 = band_edges_m(8.0, 0.0, 3.5, RADIO)
    assert pl2 < pl and pr2 > pr


@pytest.mark.parametrize("g_db", [-20.0, -3.0, 0.0, 0.7, 15.0])
def test_inverse_gap_map_inverts_the_model(g_db):
    x = inverse_gap_m(g_db, 1.3, 3.2, RADIO)
    assert float(model_gap_db(x, 1.3, 3.2, RADIO)) == pytest.approx(g_db, abs=1e-9)


def test_gap_threshold_rules():
    assert gap_threshold_db(0.5, Joint()) == pytest.approx(6.5)
    assert gap_threshold_db(0.5, Joint(gaph_rule="narrow")) == pytest.approx(5.5)
    assert gap_threshold_db(9.0, Joint(gaph_rule="narrow")) == pytest.approx(1.0)


def test_fit_recovers_exact_model_from_noise_free_gaps():
    x = np.linspace(300, 700, 50)
    r = log_ratio(x, RADIO)
    g = model_gap_db(x, 1.7, 4.2, RADIO)
    sums = (x.size, r.sum(), (r * r).sum(), g.sum(), (r * g).sum())
    a, n = fit_from_sums(*sums, Joint(), 3.5)
    assert a == pytest.approx(1.7) and n == pytest.approx(4.2)
    a, n = fit_from_sums(*sums, Joint(exponent_bounds=(2.0, 4.0)), 3.5)
    assert n == 4.0  # clipped
    a, n = fit_from_sums(*sums, Joint(band_fit="offset"), 4.2)
    assert a == pytest.approx(1.7) and n == 4.2


@pytest.mark.parametrize("m", [2, 3, 6])
@pytest.mark.parametrize("alpha", [0.05, 0.5, 0.95])
def test_wslr_predicts_exact_linear_deviations_exactly(m, alpha):
    beta0, beta1, i = 1.3, -0.8, 7
    dev = np.array([beta0 + beta1 * (i - k) for k in range(1, m + 1)])  # nearest first
    c = wslr_predict(dev[None, :], geometric_weights(m, alpha), "regression")
    assert c[0] == pytest.approx(beta0 + beta1 * i, abs=1e-12)
    # the weighted mean of a constant is the constant; one predecessor gives its value
    assert wslr_predict(np.full((1, m), 2.5), geometric_weights(m, alpha), "mean")[0] == pytest.approx(2.5)
    assert wslr_predict(dev[None, :1], geometric_weights(m, alpha), "regression")[0] == pytest.approx(dev[0])


def test_geometric_weights():
    w = geometric_weights(4, 0.3)
    assert w.sum() == pytest.approx(1.0)
    assert w[1] / w[0] == pytest.approx(0.7)
    with pytest.raises(ValueError):
        geometric_weights(0, 0.3)
    with pytest.raises(ValueError):
        geometric_weights(3, 1.0)


def test_position_correction_piecewise():
    a, n, gaph = 0.0, 3.5, 6.5
    pl, pr = band_edges_m(gaph, a, n, RADIO)
    xm, pr_retry = 0.5 * (pl + pr), pr - 20.0
    args = (xm, pl, pr_retry, gaph, a, n, 0.5, RADIO)
    assert position_correction_m(0.3, *args) == 0.0  # dead zone
    assert position_correction_m(9.0, *args) == pytest.approx(pr_retry - xm)
    assert position_correction_m(-9.0, *args) == pytest.approx(pl - xm)
    dx = float(position_correction_m(2.0, *args))  # serving stronger: later
    assert dx > 0
    assert float(model_gap_db(xm + dx, a, n, RADIO)) + 2.0 == pytest.approx(
        float(model_gap_db(xm, a, n, RADIO)), abs=1e-9
    )


def test_first_attempt_bound_closed_form_against_sampling():
    """Φ(9/8.49) − Φ(−11/8.49) = 0.758 at σ = 6 dB, against sampled gaps through the full
    SINR rule (noise included) at X_c."""
    from railradio.handover.bounds import first_attempt_success_at_centre, gap_window_db
    from railradio.handover.params import Radio
    from railradio.handover.radio import mean_rsrp_dbm, sinr_db

    rd = Radio(shadow_sigma_db=6.0)
    lo, hi = gap_window_db(rd)
    assert lo == pytest.approx(-11.01, abs=0.01) and hi == pytest.approx(9.01, abs=0.01)
    p = first_attempt_success_at_centre(rd)
    assert p == pytest.approx(0.758, abs=0.001)
    rng = np.random.default_rng(3)
    p_s, p_t = mean_rsrp_dbm(rd.overlap_centre_m, rd)
    z = rng.normal(0.0, rd.shadow_sigma_db, size=(2, 400_000))
    ok = (sinr_db(p_s - z[0], p_t - z[1], rd) >= rd.q_out_db) & (sinr_db(p_t - z[1], p_s - z[0], rd) >= rd.q_in_db)
    assert ok.mean() == pytest.approx(p, abs=0.004)
    with pytest.raises(ValueError, match="load_factor"):
        gap_window_db(Radio(load_factor=0.0))
