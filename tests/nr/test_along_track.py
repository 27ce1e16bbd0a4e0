"""Along-track and cross-track errors (railradio.nr.study.along_track): the protection level's
bookkeeping, the keys, and the free filter's anchor at the headline."""

import json

import numpy as np
import pytest
import xarray as xr
from scipy.stats import norm

from railradio.nr.study.along_track import (
    GATES,
    IMM_FILTERS,
    MEASUREMENTS,
    MODELS,
    RECEIVERS,
    RISKS,
    imm_along,
    key_numbers,
    protection,
)


def test_protection_level_counts_exceedances_and_judges_the_level():
    rng = np.random.default_rng(3)
    sigma = np.full(40_000, 0.2)
    e = sigma * rng.standard_normal(sigma.size)  # a consistent filter: e ~ N(0, σ²)
    p = protection(e, sigma, 1e-3)
    assert p["k"] == pytest.approx(norm.isf(5e-4)) and p["pl_median_m"] == pytest.approx(0.2 * p["k"])
    assert p["n_mi"] == int(np.sum(np.abs(e) > 0.2 * p["k"])) and p["mi_rate"] == p["n_mi"] / 40_000
    assert p["mi_lo"] < p["mi_rate"] < p["mi_hi"]
    assert p["mi_lo"] < 1e-3 < p["mi_hi"] and p["verdict"] == 0  # a consistent filter: undecided
    # a generous level holds, one from a σ half the truth's fails
    assert protection(e, 2 * sigma, 1e-3)["verdict"] == 1
    bad = protection(2 * e, sigma, 1e-3)
    assert bad["mi_lo"] > 1e-3 and bad["verdict"] == -1
    # too short a run cannot hold at 1e-5 even without an exceedance (rule of three)
    short = protection(np.zeros(1000), np.ones(1000), 1e-5)
    assert short["n_mi"] == 0 and short["mi_lo"] == 0 and short["mi_hi"] > 1e-5 and short["verdict"] == 0
    # no position counts as misleading
    e2 = np.zeros(100)
    e2[0] = np.nan
    assert protection(e2, np.ones(100), 1e-3)["n_mi"] == 1
    with pytest.raises(ValueError, match="risk"):
        protection(e, sigma, 0.0)
    with pytest.raises(ValueError, match="shape"):
        protection(e, sigma[:-1], 1e-3)


def _dataset(lost: float = 0.0) -> xr.Dataset:
    shape = (len(RECEIVERS), len(MEASUREMENTS), len(GATES), len(MODELS))
    base = {k: np.full(shape, 0.3) for k in ("along_mean_m", "along_p95_m", "cross_mean_m", "cross_p95_m")}
    base |= {"err_mean_m": np.full(shape, 0.4), "lost_frac": np.full(shape, lost), "q": np.full(shape, 0.01)}
    base |= {"nees_median": np.full(shape, 0.45)}
    base["along_mean_m"][:, :, 1] = 0.7  # the ungated trackers
    risk = {k: np.full(shape + (len(RISKS),), 0.5) for k in ("pl_median_m", "pl_p95_m")}
    risk |= {k: np.full(shape + (len(RISKS),), 1e-3) for k in ("mi_rate", "mi_lo", "mi_hi")}
    risk |= {"verdict": np.zeros(shape + (len(RISKS),)), "n_scored": np.full(shape + (len(RISKS),), 17_175.0)}
    dims = ("receiver", "measurements", "gate", "model")
    data = {k: (dims, v) for k, v in base.items()} | {k: (dims + ("risk",), v) for k, v in risk.items()}
    imm = {"along_mean_m": 0.2, "along_p95_m": 0.5, "cross_mean_m": 0.3, "cross_p95_m": 0.6, "err_mean_m": 0.4}
    data |= {f"imm_{k}": (("filter",), np.full(len(IMM_FILTERS), v)) for k, v in imm.items()}
    data["imm_lost_frac"] = (("filter",), np.array([0.0, 0.0, lost]))
    coords = {
        "receiver": list(RECEIVERS),
        "measurements": list(MEASUREMENTS),
        "gate": [int(g) for g in GATES],
        "model": list(MODELS),
        "risk": list(RISKS),
        "filter": list(IMM_FILTERS),
    }
    return xr.Dataset(data, coords=coords, attrs={"skip_s": 5.0, "level": 0.95})


def test_key_numbers_name_every_tracker_and_null_a_lost_accuracy():
    k = key_numbers(_dataset())
    assert k["nr.along.robust.aod_toa.track.along_m.mean"]["value"] == 0.3
    assert k["nr.along.robust.aod_toa.ungated.track.along_m.mean"]["value"] == 0.7
    assert "nr.along.robust.aod_toa.track.cross_m.mean" not in k  # ŷ = 0 by construction
    assert "nr.along.robust.aod_toa.ungated.track.cross_m.mean" not in k
    assert k["nr.along.source.toa.free.cross_m.mean"]["value"] == 0.3
    assert k["nr.along.source.toa.ungated.free.cross_m.mean"]["value"] == 0.3
    assert k["nr.along.imm.rts.along_m.p95"]["value"] == 0.5 and k["nr.along.imm.imm.cross_m.mean"]["value"] == 0.3
    assert k["nr.along.robust.aod_toa.track.risk_e5.pl_m.median"]["value"] == 0.5
    assert k["nr.along.robust.aod_toa.free.risk_e3.verdict"]["value"] == 0
    assert k["nr.along.robust.aod_toa.n_scored"]["value"] == 17_175
    n_trackers = len(RECEIVERS) * len(MEASUREMENTS) * len(GATES)
    assert len(k) == n_trackers * 7 + len(IMM_FILTERS) * 4 + 1 + len(MODELS) * len(RISKS) * 5
    lost = key_numbers(_dataset(lost=0.2))
    assert lost["nr.along.robust.aod.free.along_m.mean"]["value"] is None
    assert lost["nr.along.robust.aod.free.lost_frac"]["value"] == 0.2
    assert lost["nr.along.robust.aod_toa.track.risk_e3.pl_m.median"]["value"] is None
    assert lost["nr.along.imm.rts.along_m.mean"]["value"] is None and lost["nr.along.imm.imm.along_m.mean"]["value"]
    # without the IMM runs, no IMM keys
    assert not [n for n in key_numbers(_dataset().drop_dims("filter")) if n.startswith("nr.along.imm.")]


def test_imm_errors_split_into_along_and_across_the_track():
    # a filter 0.3 m ahead of the train and 0.4 m beside the track: 2-D error 0.5 m
    t = np.arange(100) * 0.1
    along = np.full((len(IMM_FILTERS), t.size), 0.3)
    along[1] = -0.3  # behind, for the IMM
    pos = np.full((len(IMM_FILTERS), t.size), 0.5)
    pos[2, -10:] = 200.0  # the smoother loses the last second (spacing 300 m: lost above 150 m)
    ds = xr.Dataset(
        {"along_err": (("filter", "epoch"), along), "pos_err": (("filter", "epoch"), pos), "t": (("epoch",), t)},
        coords={"filter": list(IMM_FILTERS)},
    )
    out = imm_along([ds, ds], spacing_m=300.0)
    assert out["along_mean_m"][:2] == pytest.approx([0.3, 0.3])
    assert out["cross_mean_m"][:2] == pytest.approx([0.4, 0.4])
    assert out["lost_frac"] == pytest.approx([0.0, 0.0, 10 / 50])  # of the 50 epochs after SKIP_S = 5 s
    assert out["err_mean_m"][0] == pytest.approx(0.5)


@pytest.mark.slow
def test_the_free_filter_is_the_headline_tracker(ci_run):
    # the free 2-D filter here is the main run's tracker, run alike: its 2-D error is the
    # headline's, the IMM runs' EKF's too, and the track-bound filter shares its q
    k = json.loads((ci_run / "results/key_numbers.json").read_text(encoding="utf-8"))
    with xr.open_dataset(ci_run / "results/nr/along/along_track.nc") as at:
        free = at.sel(receiver="robust", measurements="aod_toa", gate=1, model="free")
        headline = k["nr.robust.track.aod_toa_gated.err_m.mean"]
        if headline["value"] is not None:
            assert float(free["err_mean_m"]) == pytest.approx(headline["value"], rel=1e-9)
        assert float(free["lost_frac"]) == pytest.approx(headline["lost_frac"], abs=1e-12)
        # the IMM runs' EKF is the same tracker (nr.imm.receiver: ours), split from its stored errors
        for v in ("along_mean_m", "cross_mean_m", "err_mean_m", "lost_frac"):
            np.testing.assert_allclose(float(at[f"imm_{v}"].sel(filter="ekf")), float(free[v]), rtol=1e-12)
        q = at["q"].sel(receiver="robust", measurements="aod_toa", gate=1)
        assert float(q.sel(model="track")) == float(q.sel(model="free")) == k["nr.robust.cal.aod_toa_gated.q"]["value"]
