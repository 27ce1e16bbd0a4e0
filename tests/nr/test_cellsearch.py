"""The cell search names the RRHs the receiver measures from its own bursts: no truth in
the estimates, results independent of the shard count, the list follows the train."""

import dataclasses

import numpy as np
import pytest
import yaml

from railradio.nr.channel.geometry import Deployment
from railradio.nr.engine import epochs as epochs_mod
from railradio.nr.engine import simulate as sim
from railradio.nr.receiver.cellsearch import CellSearch, CellSearchConfig, neighbour_list, ss_rsrp_db, warmup_start
from railradio.nr.receiver.correlator import BlockCorrelation
from railradio.rng import spawn_key

from ..conftest import ROOT

ESTIMATES = ("rrh", "acquired", "ss_rsrp", "aod_hat", "toa_hat", "peak", "best_score", "n_detected")
"""Everything the receiver measured (the rest of a shard dataset is truth, for scoring)."""


def _scenario(**cell_search):
    nr = yaml.safe_load((ROOT / "config/config.yaml").read_text())["nr"]
    nr["cell_search"] = nr["cell_search"] | cell_search
    return sim.scenario_from_config(nr)


def test_neighbour_list_and_warmup():
    dep = Deployment()
    np.testing.assert_array_equal(neighbour_list(dep, 10, 6), [10, 9, 11, 8, 12, 7])
    np.testing.assert_array_equal(neighbour_list(dep, 0, 3), [0, 1, 2])
    assert neighbour_list(dep, dep.n_rrh - 1, 2).tolist() == [dep.n_rrh - 1, dep.n_rrh - 2]
    with pytest.raises(ValueError, match="anchor"):
        neighbour_list(dep, dep.n_rrh, 6)
    assert [warmup_start(e, 100) for e in (0, 99, 100, 250)] == [0, 0, 100, 200]
    with pytest.raises(ValueError, match="acquire_every"):
        CellSearchConfig(acquire_every=0)
    with pytest.raises(ValueError, match="confirm_epochs"):
        CellSearchConfig(confirm_epochs=1.5)


class _FakeCorrelator:
    """Detects exactly the PCIs in ``strong`` (η = their power), the same on every block."""

    def __init__(self, n_blocks=4):
        self.n_blocks, self.strong = n_blocks, {}

    def correlate(self, z, s_min, n_id1, n_id2, zf=None):
        pci = 3 * np.asarray(n_id1) + np.asarray(n_id2)
        eta = np.array([[self.strong.get(int(p), 0.5)] * self.n_blocks for p in pci])
        det = eta > 1.0
        nan = np.full(len(pci), np.nan)
        return BlockCorrelation(eta, eta * 0, eta * 0 + 1, det, nan, nan, nan)


def test_the_list_moves_only_after_confirmation_and_searches_when_the_anchor_is_lost():
    dep = Deployment()
    cor = _FakeCorrelator()
    cs = CellSearch(CellSearchConfig(acquire_every=1000, confirm_epochs=3, lost_epochs=2), dep, cor)
    cor.strong = {20: 10.0, 21: 5.0}
    cand, acq = cs.candidates(0, None, 0)
    assert acq and cs.anchor == 20 and cand[0] == 20

    n1, n2 = dep.n_id()

    def step(e):
        cand, acq = cs.candidates(e, None, 0)
        cs.update(cand, ss_rsrp_db(cor.correlate(None, 0, n1[cand], n2[cand])))
        return cand, acq

    cor.strong = {20: 5.0, 21: 10.0}  # 21 becomes the strongest: confirmed after 3 epochs
    for e in (1, 2):
        step(e)
        assert cs.anchor == 20
    step(3)
    assert cs.anchor == 21
    cand, acq = step(4)
    assert cand[0] == 21 and not acq
    cor.strong = {40: 10.0}  # nothing of the list detected: a blind search after 2 epochs
    step(5)
    assert not cs.searching
    step(6)
    assert cs.searching
    cand, acq = step(7)
    assert acq and cs.anchor == 40 and cand[0] == 40


def test_estimates_see_no_truth(monkeypatch):
    """The measurements are bit-identical when everything the synthesis knows (position,
    speed, acceleration, every link's large-scale truth, the network's serving cell) is
    replaced by NaN (-1) once the burst is made: the estimator gets the burst, the deployment and its own state only."""
    scn = _scenario(acquire_every=20)
    epochs, key = np.arange(2430, 2450), spawn_key("nr", 0)
    ref = epochs_mod.simulate_epochs(scn, epochs, 7, key)
    from railradio.nr.engine import SpectralSynthesis  # the study's synthesis

    real_call = SpectralSynthesis.__call__

    def blinded(self, epoch):
        b = real_call(self, epoch)
        lb = b.links
        nan = {
            f.name: np.full(np.shape(getattr(lb, f.name)), np.nan)
            for f in dataclasses.fields(lb)
            if f.name not in ("rrh", "links", "panel", "link_rrh") and getattr(lb, f.name) is not None
        }
        return sim.Burst(b.z, b.s_min, np.nan, np.nan, np.nan, dataclasses.replace(lb, **nan), -1)

    monkeypatch.setattr(SpectralSynthesis, "__call__", blinded)
    got = epochs_mod.simulate_epochs(scn, epochs, 7, key)
    assert np.isnan(got["x_true"]).all() and np.isnan(got["d3d"]).all()
    assert int(ref["acquired"].sum()) >= 1 and int(ref["n_detected"].sum()) > 0
    for name in ESTIMATES:
        np.testing.assert_array_equal(got[name].values, ref[name].values, err_msg=name)


def test_estimates_identical_for_any_shard_count():
    """Shards of 1, 2 and 5 parts give the same measurements, across fixed acquisitions
    (every 7 epochs here) and confirmed hand-overs of the list."""
    scn = _scenario(acquire_every=7)
    first, n, key = 2400, 30, spawn_key("nr", 0)
    runs = {}
    for n_shards in (1, 2, 5):
        parts = [
            epochs_mod.simulate_epochs(scn, first + epochs_mod.shard_epochs(n, n_shards, s), 5, key)
            for s in range(n_shards)
        ]
        runs[n_shards] = {
            name: np.concatenate([p[name].values for p in parts], axis=parts[0][name].dims.index("epoch"))
            for name in ESTIMATES
        }
    ref = runs[1]
    assert ref["acquired"].sum() >= 4
    for n_shards in (2, 5):
        for name in ESTIMATES:
            np.testing.assert_array_equal(runs[n_shards][name], ref[name], err_msg=f"{n_shards} shards: {name}")


def test_the_list_follows_the_train():
    """Scored with the truth: over 12 s at ~360 km/h (2.4 RRH spacings) the neighbour list
    holds the three RRHs nearest the train at every epoch, the anchor never lies more than
    two spacings away (the RRH beside the train is seen through the flank of the train's
    panels, tens of dB down, so the anchor is often the next one), and it moves along."""
    scn = _scenario()
    dep = scn.deployment
    ds = epochs_mod.simulate_epochs(scn, np.arange(2300, 2420), 3, spawn_key("nr", 2))
    x = ds["x_true"].values
    near3 = np.argsort(np.abs(dep.x_m[None, :] - x[:, None]), axis=1)[:, :3]
    lists = ds["rrh"].values
    assert all(set(n) <= set(lst) for n, lst in zip(near3, lists, strict=True))
    anchor = lists[:, 0]
    assert np.abs(dep.x_m[anchor] - x).max() <= 2 * dep.spacing_m
    assert np.unique(anchor).size >= 3
