"""Per-epoch simulation: an epoch's result does not depend on the shard it falls in."""

import logging

import numpy as np
import pytest
import xarray as xr
import yaml

from railradio.nr.engine.epochs import shard_epochs, shard_period, simulate_epochs
from railradio.nr.engine.simulate import scenario_from_config

from ..conftest import ROOT


def _scenario():
    with open(ROOT / "config/config.yaml") as fh:
        return scenario_from_config(yaml.safe_load(fh)["nr"])


def test_epoch_results_independent_of_sharding():
    scn = _scenario()
    a = simulate_epochs(scn, np.array([2001]), 5, (0, 7))
    b = simulate_epochs(scn, np.array([1999, 2000, 2001]), 5, (0, 7)).sel(epoch=[2001])
    for name in ("toa_hat", "aod_hat", "n_detected", "d3d", "rx_power"):
        xr.testing.assert_equal(a[name], b[name])
    c = simulate_epochs(scn, np.array([2001]), 6, (0, 7))  # another seed: other draws
    assert not np.array_equal(a["peak"].values, c["peak"].values)


def test_shards_cover_the_track_once():
    got = np.concatenate([shard_epochs(5775, 12, s) for s in range(12)])
    np.testing.assert_array_equal(got, np.arange(5775))


@pytest.mark.parametrize(("n_epochs", "n_shards"), [(5775, 4), (5775, 48), (2500, 10), (1000, 10), (160, 2)])
def test_shards_start_where_the_receiver_restarts(n_epochs, n_shards):
    """Every shard starts on a multiple of the restart period (no warm-up replayed) when the
    run has at least one period per shard; else near-equal blocks. Either way the shards
    cover the run once and none is empty."""
    with open(ROOT / "config/config.yaml") as fh:
        period = shard_period(yaml.safe_load(fh)["nr"])
    assert period == 100
    parts = [shard_epochs(n_epochs, n_shards, s, period) for s in range(n_shards)]
    np.testing.assert_array_equal(np.concatenate(parts), np.arange(n_epochs))
    assert all(p.size for p in parts)
    if n_epochs // period >= n_shards:
        assert all(p[0] % period == 0 for p in parts)
    with pytest.raises(ValueError, match="period"):
        shard_epochs(n_epochs, n_shards, 0, 0)


def test_a_long_shard_reports_its_progress(caplog):
    """simulate_epochs logs epochs done, rate and ETA (here after every epoch)."""
    scn = _scenario()
    with caplog.at_level(logging.INFO, logger="railradio.nr"):
        simulate_epochs(scn, np.array([2000, 2001]), 5, (0, 7), progress_every_s=0.0)
    lines = [r.getMessage() for r in caplog.records if r.name == "railradio.nr"]
    assert len(lines) == 2 and lines[-1].startswith("epochs 2/2") and "ETA" in lines[-1]


def test_data_beam_policies_and_geometry_bounded_window():
    import dataclasses

    import pytest

    from railradio.constants import SPEED_OF_LIGHT_M_S
    from railradio.nr.channel.link import ShadowingMap, link_budget
    from railradio.nr.synthesis.synthesizer import Synthesizer
    from railradio.nr.waveform.numerology import SAMPLE_RATE_HZ
    from railradio.nr.waveform.ssb import qpsk_pool

    scn = _scenario()
    dep = scn.deployment
    lb = link_budget(
        5100.0, 80.0, dep, scn.radio, scn.rrh_array, scn.train_array, ShadowingMap(1, (0,), dep, scn.radio)
    )
    pool = qpsk_pool(np.random.default_rng(0), 16)
    out = {}
    for policy in ("train", "random", "none"):  # (the serving policy: tests/nr/test_traffic.py)
        syn = Synthesizer(scn.receiver, scn.profile, pool, scn.n_sinusoids, scn.full_channel_range_m, policy)
        draws = syn.draws(lb.links, np.random.default_rng(1))
        out[policy] = syn(lb.links, None, 10.0, noise=False, draws=draws)[0]
        sp = syn.span(float(lb.links.tau_s.max()))
    # sample ranges of symbols without an SS block, well after the largest delay
    n = scn.receiver.num.n_fft
    quiet = [
        (s0, s0 + n)
        for s0, b in zip(sp["starts"][sp["n_pre"] + 20 :], sp["block_of"][sp["n_pre"] + 20 :], strict=True)
        if b < 0
    ][:5]
    p = {k: sum(np.sum(np.abs(z[a:b]) ** 2) for a, b in quiet) for k, z in out.items()}
    # data toward the train are the strongest; with data beamed elsewhere they fall; with no
    # data only other symbols' delayed spill remains
    assert p["train"] > 3 * p["random"] > 0
    assert p["none"] < 1e-3 * p["train"]
    with pytest.raises(ValueError, match="data_beam"):
        Synthesizer(scn.receiver, scn.profile, pool, data_beam="elsewhere")
    # geometry-bounded search window: K covers delays up to the range
    with open(ROOT / "config/config.yaml") as fh:
        c = yaml.safe_load(fh)["nr"]
    c["receiver"]["search_range_m"] = 2000.0
    scn2 = scenario_from_config(c)
    k = int(np.ceil(2000.0 / SPEED_OF_LIGHT_M_S * SAMPLE_RATE_HZ))
    assert scn2.receiver.lags_full == k and all(v[1].lags_full == k for v in scn2.extra_receivers)
    assert dataclasses.replace(scn2.receiver, search_lags=None).lags_full == 6576


def test_no_data_synthesizes_only_ss_symbols_without_changing_the_burst():
    """data_beam="none" skips the symbols without an SS block; the burst equals the one
    built over every symbol with an all-zero data pool ("train" with zero data), up to the
    float32 rounding of the FFT batch."""
    from railradio.nr.channel.link import ShadowingMap, link_budget
    from railradio.nr.synthesis.synthesizer import Synthesizer
    from railradio.nr.waveform.ssb import qpsk_pool

    scn = _scenario()
    dep = scn.deployment
    lb = link_budget(
        5100.0, 80.0, dep, scn.radio, scn.rrh_array, scn.train_array, ShadowingMap(1, (0,), dep, scn.radio)
    )
    zero_pool = np.zeros_like(qpsk_pool(np.random.default_rng(0), 16))
    z = {}
    for policy in ("none", "train"):
        syn = Synthesizer(scn.receiver, scn.profile, zero_pool, scn.n_sinusoids, scn.full_channel_range_m, policy)
        z[policy] = syn(lb.links, None, 10.0, noise=False, draws=syn.draws(lb.links, np.random.default_rng(1)))[0]
    scale = np.abs(z["train"]).max()
    assert scale > 0
    np.testing.assert_allclose(z["none"], z["train"], rtol=0, atol=1e-5 * scale)
    assert not np.array_equal(z["none"], np.zeros_like(z["none"]))
