"""q as a band (railradio.nr.study.q_band): the bootstrap rule and the band's anchor."""

import json

import numpy as np
import pytest
import xarray as xr

from railradio.nr.study.q_band import band, key_numbers


def _nees(scale: float, n: int, rng: np.random.Generator) -> np.ndarray:
    """n epochs of a filter's position NEES, chi2_2 times ``scale``, correlated over ~20 epochs."""
    z = rng.standard_normal((n + 20, 2))
    z = np.array([z[i : i + 20].mean(axis=0) for i in range(n)]) * np.sqrt(20)
    return scale * (z**2).sum(axis=1)


def test_band_keeps_what_the_run_cannot_tell_apart_and_drops_what_it_can():
    # 1 500 epochs, 100-epoch blocks: a second consistent filter (other draws) is in the band,
    # one whose NEES is 3 times too large (cost log 3 = 1.1) is not; q_hat always is
    rng = np.random.default_rng(7)
    nees = np.stack([_nees(1.0, 1500, rng), _nees(1.0, 1500, rng), _nees(3.0, 1500, rng)])
    nees[:, :5] = np.nan  # the track starts late
    inb, lo, hi = band(nees, 0, 100, 400, np.random.default_rng(1))
    assert inb.tolist() == [True, True, False]
    assert lo[2] > 0 and lo[1] < 0 < hi[1] and lo[0] == hi[0] == 0
    assert band(nees, 2, 100, 400, np.random.default_rng(1))[0][2]
    with pytest.raises(ValueError, match="block"):
        band(nees, 0, 0, 400, np.random.default_rng(1))
    with pytest.raises(ValueError, match="shorter"):
        band(nees[:, :50], 0, 100, 400, np.random.default_rng(1))


def test_key_numbers_span_the_band_and_null_a_lost_accuracy():
    qb = xr.Dataset(
        {
            "cost": ("q", [0.3, 0.03, 0.05, 2.0]),
            "in_band": ("q", np.array([1, 1, 1, 0], np.int8)),
            "lost_frac": ("q", [0.0, 0.0, 0.0, 0.5]),
            "err_mean_m": ("q", [0.38, 0.44, 0.51, 9.0]),
            "err_p95_m": ("q", [0.90, 1.01, 1.19, 30.0]),
        },
        coords={"q": [0.001, 0.01, 0.1, 1.0]},
        attrs={"q_hat": 0.01},
    )
    k = {n: v["value"] for n, v in key_numbers(qb).items()}
    assert (k["nr.qband.q_lo"], k["nr.qband.q_hi"], k["nr.qband.n_in_band"], k["nr.qband.n_q"]) == (0.001, 0.1, 3, 4)
    assert (k["nr.qband.err_m.mean.lo"], k["nr.qband.err_m.mean.hi"]) == (0.38, 0.51)
    assert k["nr.qband.err_m.p95.at_q_hat"] == 1.01
    qb["lost_frac"][2] = 0.2  # a q in the band loses its track: the band's accuracy is lost
    lost = key_numbers(qb)
    assert lost["nr.qband.err_m.mean.hi"]["value"] is None and lost["nr.qband.err_m.mean.hi"]["lost_frac"] == 0.2


@pytest.mark.slow
def test_the_band_is_anchored_at_the_headline(ci_run):
    # at the calibrated q the band's tracker is the headline tracker, run alike
    k = json.loads((ci_run / "results/key_numbers.json").read_text(encoding="utf-8"))
    for stat in ("mean", "p95"):
        band, headline = k[f"nr.qband.err_m.{stat}.at_q_hat"], k[f"nr.robust.track.aod_toa_gated.err_m.{stat}"]
        assert band.get("lost_frac") == headline.get("lost_frac")
        if headline["value"] is None:  # lost at CI scale: both null
            assert band["value"] is None
        else:
            assert band["value"] == pytest.approx(headline["value"], rel=1e-12)
    assert k["nr.qband.q_hat"]["value"] == k["nr.robust.cal.aod_toa_gated.q"]["value"]
    assert k["nr.qband.q_lo"]["value"] <= k["nr.qband.q_hat"]["value"] <= k["nr.qband.q_hi"]["value"]
