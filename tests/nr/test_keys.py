"""nr key numbers from synthetic track datasets: pooling, percentiles, spread."""
import numpy as np
import xarray as xr

from railradio.nr.keys import key_numbers


def _track(err_value: float, n: int = 200) -> xr.Dataset:
    rx, var = ["seed", "robust"], ["aod", "toa", "aod_toa"]
    pos = np.full((2, 3, 2, n), err_value)
    return xr.Dataset(
        {"pos_err": (("receiver", "variant", "gate", "epoch"), pos),
         "snap_err": (("receiver", "variant", "epoch"), pos[:, :, 0]),
         "aod_err": (("receiver", "epoch", "slot"), np.full((2, n, 3), np.radians(0.5))),
         "range_err": (("receiver", "epoch", "slot"), np.where(np.arange(3) == 2, np.nan, 0.4) * np.ones((2, n, 3))),
         "t": (("epoch",), np.arange(n) * 0.1),
         "sir_best": (("epoch",), np.full(n, 3.0))},
        coords={"receiver": rx, "variant": var, "gate": [0, 1]})


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
