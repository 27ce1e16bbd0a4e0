"""The burst engine's shared receivers (railradio.nr.engine): its kernels against the
formulations they replace, and the receivers against the study's Correlator/Estimator on
paper-scale bursts, equal to float32 rounding."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.fft as sfft
import yaml

from railradio.nr.engine import SharedEstimator, SpectralSynthesis
from railradio.nr.engine.equivalence import compare_decisions, engine_decisions
from railradio.nr.engine.simulate import Estimator, Synthesis, scenario_from_config
from railradio.nr.receiver import SharedCorrelation, front_end, kernels
from railradio.nr.receiver import kernels as study_kernels
from railradio.nr.receiver.correlator import Correlator
from railradio.nr.receiver.frontend import project, upsample
from railradio.nr.synthesis import kernels as synthesis_kernels
from railradio.nr.synthesis.band_edges import BandEdges
from railradio.nr.waveform.numerology import SAMPLE_RATE_HZ, period_length
from railradio.rng import spawn_key

from ..conftest import ROOT


def _crandn(rng, *shape):
    return (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)).astype(np.complex64)


def test_row_stats_and_cfar_peak_equal_the_study_kernels(rng):
    c = _crandn(rng, 12, 300)
    r, edge, stats = np.empty((12, 200), np.float32), np.empty((12, 2), np.float32), np.empty((12, 4))
    kernels.row_stats(c, c, False, 200, r, edge, stats)
    r0, mu, sigma, eta, arg = study_kernels.magnitude_stats(c, 200)
    np.testing.assert_array_equal(r, r0)
    np.testing.assert_array_equal(stats, np.stack([mu, sigma, eta, arg], axis=1))
    np.testing.assert_allclose(edge, np.abs(c[:, [299, 200]]), rtol=1e-6)
    for window, guard in ((16, 2), (64, 8), (150, 30)):  # the last: every window clamped
        got = kernels.ca_cfar_peak(r, window, guard)
        for a, b in zip(got, study_kernels.local_mean_argmax(r, window, guard), strict=True):
            np.testing.assert_array_equal(a, b)
    d = _crandn(rng, 12, 300)
    kernels.row_stats(c, d, True, 200, r, edge, stats)
    np.testing.assert_allclose(r, np.abs(c[:, :200] + d[:, :200]), rtol=1e-6)


def test_between_lags_is_the_band_limited_correlation(rng):
    n, d = 256, 4
    zf, spec = _crandn(rng, 5, n), _crandn(rng, 3, n)
    blocks, cells, k0 = np.array([0, 4, 2]), np.array([2, 0, 1]), np.array([0, 77, 255])
    roots = np.exp(2j * np.pi * np.arange(n) / n).astype(np.complex64)
    f = np.fft.fftfreq(n, 1.0 / n)
    theta = 2 * np.pi * np.outer(np.arange(1, d) / d, f) / n
    cs = np.concatenate([np.cos(theta), np.sin(theta)]).astype(np.float32)
    got = kernels.between_lags(zf, spec, blocks, cells, k0, roots, cs)
    offsets = np.concatenate([-np.arange(d - 1, 0, -1), np.arange(1, d)]) / d
    p = zf[blocks].astype(complex) * spec[cells]
    want = np.abs(np.exp(2j * np.pi * np.outer(k0[:, None] + offsets[None, :], f).reshape(3, -1, n) / n) @ p[..., None])
    np.testing.assert_allclose(got, want[..., 0] / n, rtol=2e-5)


def test_pss_part_plus_sss_part_is_the_whole_reference():
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text(encoding="utf-8"))
    scn = scenario_from_config(cfg["nr"])
    rc = dataclasses.replace(scn.receiver, decimation=2)
    cor = Correlator(rc, template_decimation=8)
    sh = SharedCorrelation([cor])
    whole = cor.spectrum(17, 2)
    np.testing.assert_allclose(sh.part("pss", 17, 2) + sh.part("sss", 17, 2), whole, atol=1e-4 * np.abs(whole).max())
    with pytest.raises(ValueError, match="share"):
        SharedCorrelation([cor, Correlator(dataclasses.replace(rc, n_blocks=8), template_decimation=8)])
    with pytest.raises(ValueError, match="at least one"):
        SharedCorrelation([])


@pytest.fixture(scope="module")
def paper_epochs():
    """Four paper-scale epochs of realization 0 (an acquisition epoch first), both estimators."""
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text(encoding="utf-8"))
    scn = scenario_from_config(cfg["nr"])
    syn = Synthesis(scn, cfg["seed"], spawn_key("nr", 0))
    old, new = Estimator(scn), SharedEstimator(scn)
    old.start(2500)
    new.start(2500)
    out = []
    for e in range(2500, 2504):
        b = syn(e)
        out.append((old(e, b.z, b.s_min, keep_corr=True), new(e, b.z, b.s_min, keep_corr=True)))
    return out


def test_shared_receivers_equal_the_study_receivers_to_float32_rounding(paper_epochs):
    """Every receiver (the source's and the robust one) and the cell search on the same
    bursts: the same lists and detections, TOAs to the lag, AODs and levels to float32
    rounding."""
    for mo, mn in paper_epochs:
        np.testing.assert_array_equal(mn.cand, mo.cand)
        assert mn.acquired == mo.acquired
        np.testing.assert_array_equal(mn.n_detected, mo.n_detected)
        np.testing.assert_array_equal(mn.toa_s * SAMPLE_RATE_HZ, mo.toa_s * SAMPLE_RATE_HZ)
        np.testing.assert_allclose(mn.aod_rad, mo.aod_rad, rtol=0, atol=1e-6)
        np.testing.assert_allclose(mn.ss_rsrp_db, mo.ss_rsrp_db, rtol=0, atol=1e-4)
        np.testing.assert_allclose(mn.peak, mo.peak, rtol=1e-4)
        np.testing.assert_allclose(mn.best_score, mo.best_score, rtol=1e-4)
        np.testing.assert_allclose(mn.corr, mo.corr, rtol=1e-4, atol=1e-5 * mo.corr.max())
    assert paper_epochs[0][0].acquired


def test_front_end_is_project_edges_upsample_in_one_pass(rng):
    z = _crandn(rng, 96)
    edges = _crandn(rng, 24) * 0.1
    want = upsample(project(z, 4) + sfft.ifft(edges).astype(np.complex64), 3)
    np.testing.assert_allclose(front_end(z, 4, 3, edges), want, rtol=0, atol=1e-6 * np.abs(want).max())
    np.testing.assert_allclose(front_end(z, 2, 1), project(z, 2), rtol=0, atol=1e-6)
    with pytest.raises(ValueError, match="multiple of down"):
        front_end(z[:95], 4, 1)
    with pytest.raises(ValueError, match="up must be"):
        front_end(z, 4, 0)
    with pytest.raises(ValueError, match="edges must have 24"):
        front_end(z, 4, 1, edges[:5])


def test_the_front_end_pads_the_burst_to_a_period_of_small_factors(rng):
    """A burst of 62 689 = 11·41·139 samples at F_s/8 (paper scale) is filtered over a period
    of 64 000 = 2^9·5^3; lengths of factors 2, 3 and 5 are kept; the padding is zeros after
    the burst (padding the input by hand changes nothing)."""
    assert period_length(62689) == 64000
    assert [period_length(m) for m in (1, 7, 24, 31, 4928)] == [1, 8, 24, 32, 5000]
    for bad in (0, -3, 2.0, True):
        with pytest.raises(ValueError, match="m must be an integer"):
            period_length(bad)
    z = _crandn(rng, 4 * 31)
    edges = _crandn(rng, 32) * 0.1
    out = front_end(z, 4, 3, edges)
    assert out.shape == (3 * 32,)
    padded = np.pad(z, (0, 4))
    np.testing.assert_allclose(out, front_end(padded, 4, 3, edges), rtol=0, atol=1e-6 * np.abs(out).max())
    np.testing.assert_allclose(project(z, 4), project(padded, 4), rtol=0, atol=1e-6 * np.abs(out).max())
    with pytest.raises(ValueError, match="edges must have 32"):
        front_end(z, 4, 1, edges[:31])


def test_spectral_synthesis_is_the_study_burst_on_the_lag_grid():
    """The paper-scale burst (band synthesis, its edges, the front end) brought to the lag
    grid in one spectral pass equals the study's three steps to float32 rounding."""
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text(encoding="utf-8"))
    scn = scenario_from_config(cfg["nr"])
    study = Synthesis(scn, cfg["seed"], spawn_key("nr", 0))
    engine = SpectralSynthesis(scn, cfg["seed"], spawn_key("nr", 0))
    assert engine.edges is not None and engine.up == 4
    for e in (2500, 3100):
        a, b = study(e), engine(e)
        want = upsample(a.z, 4)
        assert b.s_min == a.s_min and b.x_m == a.x_m and b.serving == a.serving
        np.testing.assert_allclose(b.z, want, rtol=0, atol=2e-6 * np.abs(want).max())


def test_scatter_rows_adds_as_band_edges_scatter(rng):
    """The compiled scatter adds a link's values around the symbol starts exactly as
    BandEdges._scatter does (strided runs, and the wrapped run past the burst's end)."""

    class _Holder:
        _rows: dict = {}

    base = np.array([0, 10, 20, 30, 41, 52, 95])  # two runs, the last wrapping past m = 100
    local = _crandn(rng, base.size, 4, 3)
    want = np.zeros((100, 3), np.complex128)
    BandEdges._scatter(_Holder(), want, base, 2, local)
    got = np.zeros((100, 3), np.complex128)
    synthesis_kernels.scatter_rows(got, base, 2, local)
    np.testing.assert_array_equal(got, want)


def test_engine_decisions_are_compared_across_versions():
    """Two dumps of the engine's decisions count what differs; dumps of another run refuse."""
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text(encoding="utf-8"))
    scn = scenario_from_config(cfg["nr"])
    a = engine_decisions(scn, cfg["seed"], spawn_key("nr", 0), np.arange(2500, 2503))
    same = compare_decisions(a, a)
    assert same["lists_changed"] == 0 and same["source"]["pairs"] > 0
    assert all(same[n][k] == 0 for n in a["names"] for k in ("detections_changed", "toa_changed", "aod_changed"))
    b = {**a, "decisions": [dict(d) for d in a["decisions"]]}
    toa = b["decisions"][1]["toa_s"].copy()
    j = np.flatnonzero(np.isfinite(toa[0]))[0]
    toa[0, j] += 2.0 / SAMPLE_RATE_HZ
    b["decisions"][1]["toa_s"] = toa
    moved = compare_decisions(a, b)
    assert moved["source"]["toa_changed"] == 1 / moved["source"]["pairs"]
    assert moved["robust"]["toa_changed"] == 0
    with pytest.raises(ValueError, match="same seed"):
        compare_decisions(a, {**a, "run": {**a["run"], "seed": a["run"]["seed"] + 1}})
    with pytest.raises(ValueError, match="same epochs"):
        compare_decisions(a, {**a, "epochs": a["epochs"] + 1})
    with pytest.raises(ValueError, match="consecutive"):
        engine_decisions(scn, cfg["seed"], spawn_key("nr", 0), np.array([2500, 2502]))
