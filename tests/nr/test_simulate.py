"""Per-epoch simulation: an epoch's result does not depend on the shard it falls in."""
import numpy as np
import xarray as xr
import yaml

from railradio.nr.simulate import scenario_from_config, shard_epochs, simulate_epochs

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
