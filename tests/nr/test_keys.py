"""nr key numbers from synthetic track datasets: pooling, percentiles, spread, lost tracks."""

import json

import numpy as np
import pytest
import xarray as xr

from railradio.keynumbers import to_latex
from railradio.nr.study.keys import key_numbers, sensitivity_key_numbers
from railradio.nr.tracking import loss


def _track(err_value: float | np.ndarray, n: int = 200, spacing_m: float = 500.0) -> xr.Dataset:
    rx, var = ["source", "robust"], ["aod", "toa", "aod_toa"]
    pos = np.broadcast_to(np.asarray(err_value, dtype=float), (2, 3, 2, n)).copy()
    ds = xr.Dataset(
        {
            "pos_err": (("receiver", "measurements", "gate", "epoch"), pos),
            "along_err": (("receiver", "measurements", "gate", "epoch"), -0.6 * pos),
            "snap_err": (("receiver", "measurements", "epoch"), pos[:, :, 0]),
            "aod_err": (("receiver", "epoch", "slot"), np.full((2, n, 3), np.radians(0.5))),
            "range_err": (("receiver", "epoch", "slot"), np.where(np.arange(3) == 2, np.nan, 0.4) * np.ones((2, n, 3))),
            "t": (("epoch",), np.arange(n) * 0.1),
            "sir_best": (("epoch",), np.full(n, 3.0)),
        },
        coords={"receiver": rx, "measurements": var, "gate": [0, 1]},
    )
    ds.attrs["config_json"] = json.dumps({"sim": {"deployment": {"spacing_m": spacing_m}}})
    return ds


def test_pooling_and_spread():
    k = key_numbers([_track(0.5), _track(1.5)])
    # the first 5 s (50 epochs) are skipped; pooled mean of 0.5 and 1.5
    assert k["nr.track.aod_toa.err_m.mean"]["value"] == 1.0
    assert k["nr.track.aod_toa.err_m.mean"]["mc_stderr"] == np.std([0.5, 1.5], ddof=1) / np.sqrt(2)
    assert k["nr.track.aod_toa.frac_submeter"]["value"] == 0.5
    assert k["nr.meas.detection_rate"]["value"] == 2 / 3
    assert abs(k["nr.meas.aod_err_deg.p95"]["value"] - 0.5) < 1e-12
    assert k["nr.track.aod_toa.err_m.mean"]["source_value"] == 0.66
    assert k["nr.robust.track.aod_toa.err_m.mean"]["source_value"] is None
    assert k["nr.link.sir_best_db.median"]["value"] == 3.0


def test_an_epoch_is_lost_beyond_half_the_rrh_spacing_or_without_a_position():
    err = np.array([0.1, 249.9, 250.0, 250.1, np.nan, 1e19])
    assert loss.lost_mask(err, 500.0).tolist() == [False, False, False, True, True, True]
    assert loss.time_to_loss_s([(np.arange(6.0), err)], 500.0) == 3.0
    assert loss.time_to_loss_s([(np.arange(3.0), err[:3])], 500.0) is None
    assert loss.accuracy(1.2, 0.0) == 1.2 and loss.accuracy(1.2, 0.01) is None
    assert loss.accuracy(2e4, 0.001) is None  # no accuracy above 10 km
    with pytest.raises(ValueError, match="spacing_m"):
        loss.lost_mask(err, 0.0)


def test_a_diverged_track_is_reported_as_lost_not_as_an_accuracy():
    """A track that diverges after 10 s (to 1e19 m) has no mean error: the all-epoch keys
    are null beside the lost share, the tracked ones describe the epochs before the loss."""
    err = np.where(np.arange(200) < 100, 0.5, 1e19)  # lost from t = 10 s on
    k = key_numbers([_track(err), _track(0.4)])
    assert k["nr.track.aod_toa.lost_frac"]["value"] == pytest.approx(100 / 300)
    assert k["nr.track.aod_toa.err_m.mean"]["value"] is None
    assert k["nr.track.aod_toa.err_m.mean"]["lost_frac"] == pytest.approx(100 / 300)
    assert k["nr.track.aod_toa.tracked.err_m.mean"]["value"] == pytest.approx((50 * 0.5 + 150 * 0.4) / 200)
    assert k["nr.track.aod_toa.time_to_loss_s"]["value"] == pytest.approx(10.0)  # the one that loses it
    assert all(e["value"] is None or e["value"] <= loss.ACCURACY_CAP_M for n, e in k.items() if "err_m" in n)
    tex = to_latex(k)
    assert r"\@namedef{kn@nr.track.aod_toa.err_m.mean}{lost (33\,\% of epochs)}" in tex
    assert r"\@namedef{knlost@nr.track.aod_toa.err_m.mean}{}" in tex
    assert r"\@namedef{knlost@nr.track.aod_toa.tracked.err_m.mean}" not in tex
    # a rarely lost track keeps its all-epoch accuracy, with the lost share beside it
    rare = np.where(np.arange(200) == 150, 1e3, 0.5)  # 1 of 300 scored epochs
    k = key_numbers([_track(rare), _track(0.5)])
    assert k["nr.track.aod_toa.err_m.mean"]["value"] == pytest.approx((299 * 0.5 + 1e3) / 300)
    assert k["nr.track.aod_toa.err_m.mean"]["lost_frac"] == pytest.approx(1 / 300)


def test_sensitivity_cases_report_lost_tracks_with_their_own_spacing():
    err = np.full(200, 300.0)  # lost with 500 m spacing, tracked with 1000 m
    k = sensitivity_key_numbers(_track(err), {"wide": _track(err, spacing_m=1000.0)}, 200)
    assert k["sens.nr.base.source.track.aod_toa.lost_frac"]["value"] == 1.0
    assert k["sens.nr.base.source.track.aod_toa.err_m.mean"]["value"] is None
    assert k["sens.nr.wide.source.track.aod_toa.lost_frac"]["value"] == 0.0
    assert k["sens.nr.wide.source.track.aod_toa.err_m.mean"]["value"] == 300.0
