"""Amplitude variants from one synthesis of the links' unit parts
(:mod:`railradio.nr.engine.variants`): each variant's burst equals its own synthesis."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import yaml

from railradio.nr.engine.frontend import SpectralSynthesis
from railradio.nr.engine.simulate import scenario_from_config
from railradio.nr.engine.variants import VariantSynthesis, check_variants
from railradio.nr.synthesis.parts import PartsSynthesizer, weigh
from railradio.rng import spawn_key

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def paper():
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text(encoding="utf-8"))
    return cfg, scenario_from_config(cfg["nr"])


def _variants(base):
    """The map's and the cases' kinds of amplitude variant: M_T, each data rule, the load,
    the Tx power; and one with another receiver (it reads the same bursts)."""
    rep = dataclasses.replace
    return [
        base,
        rep(base, rrh_array=rep(base.rrh_array, n_elements=8)),
        rep(base, rrh_array=rep(base.rrh_array, n_elements=64), data_beam="none"),
        rep(base, data_beam="train"),
        rep(base, data_beam="random", load=0.5),
        rep(base, load=0.0),
        rep(base, radio=rep(base.radio, tx_power_dbm=base.radio.tx_power_dbm - 10.0)),
        rep(base, receiver=rep(base.receiver, template="sss"), detector="cacfar"),
    ]


def test_every_variant_equals_its_own_synthesis_to_float32_rounding(paper):
    """Paper-scale epochs (an acquisition epoch, the next, one at 310 s): each variant's
    burst on the lag grid — the parts weighed by its amplitudes, its edges likewise, its front
    end — equals :class:`SpectralSynthesis` of that variant (its own draws, channel and
    noise) to float32 rounding, and so do its truth and serving cell."""
    cfg, base = paper
    scns = _variants(base)
    key = spawn_key("nr", 0)
    vs = VariantSynthesis(scns, cfg["seed"], key)
    own = [SpectralSynthesis(s, cfg["seed"], key) for s in scns]
    for e in (2500, 2501, 3100):
        got = vs(e)
        assert len(got) == len(scns)
        for i, (g, o) in enumerate(zip(got, own, strict=True)):
            want = o(e)
            assert (g.s_min, g.x_m, g.serving) == (want.s_min, want.x_m, want.serving), i
            np.testing.assert_allclose(g.z, want.z, rtol=0, atol=2e-6 * np.abs(want.z).max(), err_msg=f"variant {i}")
    # the variants do differ: M_T and the data rule change the burst far beyond rounding
    z = [b.z for b in got]
    # the variant with another receiver reads the first variant's burst, which no receiver may write
    assert z[-1] is z[0] and not z[0].flags.writeable
    assert all(zi is not z[0] for zi in z[1:-1])
    assert np.abs(z[1] - z[0]).max() > 1e-2 * np.abs(z[0]).max()
    assert np.abs(z[2] - z[0]).max() > 1e-2 * np.abs(z[0]).max()


def test_variants_must_share_the_channel(paper):
    cfg, base = paper
    check_variants(_variants(base))
    rep = dataclasses.replace
    with pytest.raises(ValueError, match="delay_spread_s"):
        check_variants([base, rep(base, delay_spread_s=2 * base.delay_spread_s)])
    with pytest.raises(ValueError, match="rrh_array"):
        check_variants([base, rep(base, rrh_array=rep(base.rrh_array, n_beams=32))])
    with pytest.raises(ValueError, match="radio"):
        check_variants([base, rep(base, radio=rep(base.radio, noise_figure_db=9.0))])
    with pytest.raises(ValueError, match="study's path"):
        check_variants([rep(base, exact_spill=False)])
    with pytest.raises(ValueError, match="at least one"):
        check_variants([])


def test_parts_reject_what_they_cannot_split(paper):
    cfg, base = paper
    syn = SpectralSynthesis(base, cfg["seed"], spawn_key("nr", 0)).syn
    args = (syn.cfg, syn.profile, np.ones((4, 4096), np.complex64))
    with pytest.raises(ValueError, match="exact_spill"):
        PartsSynthesizer(*args, exact_spill=False)
    with pytest.raises(ValueError, match="data_beam"):
        PartsSynthesizer(*args, data_beam="none", exact_spill=True)
    vs = VariantSynthesis([base], cfg["seed"], spawn_key("nr", 0))
    o = vs.own[0]
    _, _, _, lb, _ = o.advance(2500)
    draws = vs.parts.draws(lb.links, np.random.default_rng(0))
    parts = vs.parts.parts(lb.links, np.random.default_rng(1), draws, noise=False)
    with pytest.raises(ValueError, match="shape"):
        weigh(parts, np.ones((lb.links.n, 3, parts.prev.shape[2]), np.float32))


def test_variant_epochs_equal_each_variant_run_on_its_own(paper):
    """A shard of two variants and a receiver-only twin of the first (which reads its burst)
    from one synthesis gives each variant's estimates as its own run (simulate_epochs) does:
    the same neighbour lists and detections, TOAs and AODs to float32 rounding."""
    from railradio.nr.engine.epochs import simulate_epochs
    from railradio.nr.engine.variants import simulate_variant_epochs

    cfg, base = paper
    scns = _variants(base)[:2] + _variants(base)[-1:]
    epochs = np.arange(2500, 2503)  # from an acquisition epoch, as a shard starts
    key = spawn_key("nr", 0)
    got = simulate_variant_epochs(scns, epochs, cfg["seed"], key)
    for scn, ds in zip(scns, got, strict=True):
        want = simulate_epochs(scn, epochs, cfg["seed"], key)
        assert set(ds.data_vars) == set(want.data_vars)
        np.testing.assert_array_equal(ds["cand"].values, want["cand"].values)
        np.testing.assert_array_equal(ds["x_true"].values, want["x_true"].values)
        for v in ("toa_hat", "aod_hat"):
            np.testing.assert_allclose(
                ds[v].values, want[v].values, rtol=0, atol=1e-6 * np.nanmax(np.abs(want[v].values))
            )
    with pytest.raises(ValueError, match="strictly increasing"):
        simulate_variant_epochs(scns, epochs[::-1], cfg["seed"], key)


def test_variant_groups_gather_the_amplitude_variants(paper):
    import copy

    from railradio.nr.engine.variants import variant_groups

    cfg, _ = paper
    nr = cfg["nr"]

    def cell(**over):
        c = copy.deepcopy(nr)
        for section, values in over.items():
            c[section].update(values)
        return c

    configs = {
        "base": nr,
        "tdl_a": cell(channel={"tdl": "TDL-A"}),
        "mt8": cell(antenna={"rrh_elements": 8}),
        "none": cell(traffic={"data_beam": "none"}),
        "tdl_a_mt8": cell(channel={"tdl": "TDL-A"}, antenna={"rrh_elements": 8}),
    }
    assert variant_groups(configs, min_group=2) == [["base", "mt8", "none"], ["tdl_a", "tdl_a_mt8"]]
    assert variant_groups(configs, min_group=3) == [["base", "mt8", "none"]]
    assert variant_groups(configs) == []


def test_equivalence_counts_what_the_one_synthesis_changes(paper):
    """railradio.nr.engine.equivalence.compare_variants: each variant's decisions from its own
    synthesis against the one synthesis — none changed on these epochs (a measured 0 of 20 400
    candidate pairs per receiver over 100 epochs of the map's 17 cells, 2026-12-06)."""
    from railradio.nr.engine.equivalence import compare_variants

    cfg, base = paper
    res = compare_variants(_variants(base)[:2], cfg["seed"], spawn_key("nr", 0), np.arange(2500, 2502))
    assert res["epochs"] == 2 and set(res["ms_per_epoch"]) == {"own", "variants"}
    for i in ("0", "1"):
        assert res[i]["lists_changed"] == 0
        for name in ("source", "robust"):
            r = res[i][name]
            assert r["pairs"] == 12
            assert r["detections_changed"] == r["toa_changed"] == r["aod_changed"] == 0
            assert set(r["selection_changed"].values()) == {0.0}
    with pytest.raises(ValueError, match="consecutive"):
        compare_variants(_variants(base)[:2], cfg["seed"], spawn_key("nr", 0), np.array([2500, 2502]))


def test_cells_run_in_groups_or_alone_as_each_on_its_own(paper):
    """simulate_cells (the map's shard jobs): the amplitude variants together, another
    channel alone; every cell's estimates as its own run gives them."""
    from railradio.nr.engine.epochs import simulate_epochs
    from railradio.nr.engine.variants import simulate_cells

    cfg, base = paper
    rep = dataclasses.replace
    scns = {"base": base, "tdl_a": rep(base, tdl="TDL-A"), "mt8": _variants(base)[1]}
    epochs = np.arange(2500, 2502)
    key = spawn_key("nr", 0)
    got = simulate_cells(scns, epochs, cfg["seed"], key, min_group=2)
    assert list(got) == list(scns)
    for name, scn in scns.items():
        want = simulate_epochs(scn, epochs, cfg["seed"], key)
        np.testing.assert_array_equal(got[name]["cand"].values, want["cand"].values)
        np.testing.assert_allclose(got[name]["toa_hat"].values, want["toa_hat"].values, rtol=0, atol=1e-12)
    assert not np.array_equal(got["tdl_a"]["toa_hat"].values, got["base"]["toa_hat"].values)
