"""The tunnel keys: the train-length (attitude) key, a lost track reported as lost."""

import numpy as np
import pytest
import xarray as xr

from railradio.tunnel.keys import length_error_m


def test_length_error_from_head_and_tail_estimates():
    ds = xr.Dataset(
        {"kf_head": ("t", np.array([200.0, 201.0, 199.5])), "kf_tail": ("t", np.array([0.0, 0.5, 0.5]))},
        attrs={"length_m": 200.0},
    )
    np.testing.assert_allclose(length_error_m(ds), [0.0, 0.5, 1.0])


def test_a_lost_track_is_reported_as_lost_not_as_an_accuracy():
    """An error above one slot spacing after the start-up is lost; the all-epoch percentile is
    then null with the lost share beside it, and the kept epochs give the tracked accuracy."""
    import xarray as xr

    from railradio.tunnel.keys import START_S, _pooled, _track_keys, lost_epochs

    t = np.arange(0.0, 60.0, 0.05)
    ok = np.full(t.size, 1.0)
    ok[0] = 50.0  # start-up transient: not a loss
    gone = ok.copy()
    gone[t >= 30.0] = 3000.0  # the track leaves at 30 s
    rep = np.stack([ok, gone])
    assert not lost_epochs(ok, 20.0, t).any() and lost_epochs(ok, 20.0).any()
    assert lost_epochs(gone, 20.0, t).sum() == np.sum(t >= 30.0) and START_S < 30.0
    ds = xr.Dataset({"rep_err": (("realization", "time_s"), rep)}, coords={"time_s": t})
    out = {}
    _pooled(out, "tunnel.hst.err_m.p95", ds, spacing=20.0)
    _track_keys(out, "tunnel.hst", ds, 20.0)
    assert out["tunnel.hst.err_m.p95"]["value"] is None
    assert out["tunnel.hst.err_m.p95"]["lost_frac"] == pytest.approx(np.mean(t >= 30.0) / 2)
    assert out["tunnel.hst.lost_frac"]["value"] == pytest.approx(np.sum(t >= 30.0) / np.sum(t >= START_S) / 2)
    assert out["tunnel.hst.time_to_loss_s"]["value"] == pytest.approx(30.0)
    assert out["tunnel.hst.tracked.err_m.p95"]["value"] == pytest.approx(1.0)
    with pytest.raises(ValueError, match="slot_spacing_m"):
        lost_epochs(ok, 0.0)
