"""Traffic: the serving cell's data go to the train, the others' to their own users in a
share ``load`` of their slots; the network's serving cell follows the large-scale power
with a hysteresis, and its periodic restart barely changes it."""

import numpy as np
import pytest
import yaml

from railradio.nr.channel.link import Links, ShadowingMap, link_budget
from railradio.nr.channel.tdl import TdlProfile
from railradio.nr.engine.simulate import Synthesis, scenario_from_config
from railradio.nr.receiver.config import ReceiverConfig
from railradio.nr.receiver.correlator import Correlator
from railradio.nr.synthesis.reference import reference_correlation, reference_received
from railradio.nr.synthesis.synthesizer import Synthesizer
from railradio.nr.waveform.numerology import SAMPLE_RATE_HZ
from railradio.nr.waveform.ssb import qpsk_pool
from railradio.nr.waveform.traffic import ServingCell, ServingRule
from railradio.rng import spawn_key

from ..conftest import ROOT


def _scenario(**traffic):
    nr = yaml.safe_load((ROOT / "config/config.yaml").read_text())["nr"]
    nr["traffic"] = nr["traffic"] | traffic
    return scenario_from_config(nr)


def test_serving_cell_hysteresis_and_restart():
    net = ServingCell(ServingRule(hysteresis_db=3.0, reset_every=10))
    rrh = np.array([4, 5, 6])
    assert net.update(1, rrh, np.array([-60.0, -62.0, -70.0])) == 4  # no state: the strongest
    assert net.update(2, rrh, np.array([-61.0, -59.0, -70.0])) == 4  # 2 dB better: kept
    assert net.update(3, rrh, np.array([-63.0, -59.0, -70.0])) == 5  # 4 dB better: handed over
    assert net.update(4, rrh[1:], np.array([-59.0, -57.0])) == 5
    assert net.update(5, np.array([6, 7]), np.array([-70.0, -71.0])) == 6  # serving out of range
    assert net.update(10, np.array([6, 7]), np.array([-70.0, -68.0])) == 7  # restart: the strongest
    assert net.update(11, np.array([], dtype=int), np.array([])) == -1
    with pytest.raises(ValueError, match="hysteresis_db"):
        ServingRule(hysteresis_db=-1.0)
    with pytest.raises(ValueError, match="reset_every"):
        ServingRule(reset_every=0)


def test_data_policies_set_the_interference_on_the_train():
    """Power in symbols without an SS block, the train 100 m from the strongest RRH: every
    RRH beaming at the train > the serving cell at the train and the others at their users
    > the serving cell alone (load 0) > the others only (no serving cell) > no data."""
    scn = _scenario()
    dep = scn.deployment
    lb = link_budget(
        5100.0, 80.0, dep, scn.radio, scn.rrh_array, scn.train_array, ShadowingMap(1, (0,), dep, scn.radio)
    )
    serving = lb.rrh == lb.rrh[int(np.argmax(lb.rx_power_dbm))]
    pool = qpsk_pool(np.random.default_rng(0), 16)
    out = {}
    for name, policy, load, mask in (
        ("train", "train", 1.0, None),
        ("serving", "serving", 1.0, serving),
        ("others", "random", 1.0, None),
        ("alone", "serving", 0.0, serving),
        ("none", "none", 1.0, None),
    ):
        syn = Synthesizer(scn.receiver, scn.profile, pool, scn.n_sinusoids, scn.full_channel_range_m, policy, load)
        draws = syn.draws(lb.links, np.random.default_rng(1))
        out[name] = syn(lb.links, None, 10.0, noise=False, draws=draws, serving=mask)[0]
        sp = syn.span(float(lb.links.tau_s.max()))
    n = scn.receiver.num.n_fft
    quiet = [
        (s0, s0 + n)
        for s0, b in zip(sp["starts"][sp["n_pre"] + 20 :], sp["block_of"][sp["n_pre"] + 20 :], strict=True)
        if b < 0
    ][:8]
    p = {k: sum(np.sum(np.abs(z[a:b]) ** 2) for a, b in quiet) for k, z in out.items()}
    assert p["train"] > 1.05 * p["serving"]  # the neighbours' data beamed at the train
    assert p["serving"] > p["alone"] > 10 * p["others"]  # the serving cell's data dominate
    assert p["others"] > 10 * p["none"]
    with pytest.raises(ValueError, match="load"):
        Synthesizer(scn.receiver, scn.profile, pool, data_beam="serving", load=1.5)


def test_serving_policy_matches_the_reference():
    """Two cells, the first serving (data on its beam toward the train), the second at half
    load on its drawn beams: the fast synthesis and the per-sample full-rate reference agree
    on the correlation with the second cell (the bound of tests/nr/test_receiver.py)."""
    rng = np.random.default_rng(5)
    cfg = ReceiverConfig(decimation=4, n_blocks=4)
    cfg1 = ReceiverConfig(decimation=1, n_blocks=4)
    pool = qpsk_pool(rng, 16)
    los = TdlProfile("LOS", 1.0, 0.0, np.zeros(0), np.zeros(0))
    beams = np.geomspace(1.0, 0.05, 64)[None, :] * np.ones((2, 1))
    links = Links(
        n_id1=np.array([5, 9]),
        n_id2=np.array([1, 2]),
        tau_s=np.array([300.0, 900.4]) / SAMPLE_RATE_HZ,
        amp=np.array([1.0, 0.6]),
        beam_amp=beams,
        data_amp=np.array([1.0, 0.8]),
        f_los_hz=np.zeros(2),
        phase0=np.zeros(2),
        doppler_hz=0.0,
        noise_psd_w_hz=0.0,
    )
    syn = Synthesizer(cfg, los, pool, data_beam="serving", load=0.5)
    draws = syn.draws(links, rng)
    mask = np.array([True, False])
    z, s_min = syn(links, rng, noise=False, draws=draws, serving=mask)
    z1 = reference_received(cfg1, links, los, pool, draws, syn._span["symbols"], at_train=mask)
    fast = Correlator(cfg).correlate(z, s_min, np.array([9]), np.array([2]), keep_corr=True)
    ref_r = reference_correlation(cfg1, z1, s_min, 9, 2)
    err = np.abs(4 * fast.corr[0] - ref_r[:, np.arange(cfg.lags) * 4]).max() / ref_r.max()
    assert err < 0.10, err
    # the reference with every link at the train differs: the policy reached both paths
    z2 = reference_received(cfg1, links, los, pool, draws, syn._span["symbols"])
    assert np.abs(z2 - z1).max() > 0.1 * np.abs(z1).max()


def test_restarts_barely_change_the_serving_cell():
    """Over 300 s of realization 0 the serving cell with restarts every 100 epochs differs
    from the never-restarted one at < 2 % of the epochs (only where the hysteresis kept a
    weaker cell)."""
    scn = _scenario()
    epochs = range(0, 3000)
    seq = {}
    for every in (scn.serving.reset_every, 10**9):
        s = Synthesis(scn, 5, spawn_key("nr", 0))
        s.network = ServingCell(ServingRule(scn.serving.hysteresis_db, every))
        seq[every] = np.array([s.advance(e)[4] for e in epochs])
    a, b = seq.values()
    assert np.unique(b).size >= 10  # the train passes many cells
    assert (a != b).mean() < 0.02, (a != b).mean()
