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
