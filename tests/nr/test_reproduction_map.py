"""The reproduction map: its cells, the block bootstrap and the claim rule."""

import numpy as np
import pytest
import yaml

from railradio.config import ConfigError, load_schema, validate_config
from railradio.config_checks import check_config
from railradio.nr.channel.geometry import Trajectory
from railradio.nr.study import map_diagnostics as md
from railradio.nr.study import reproduction_map as rm
from railradio.rng import make_rng

from ..conftest import ROOT

SCHEMA = load_schema(ROOT / "workflow/schemas/config.schema.yaml")


def _paper():
    return validate_config(yaml.safe_load((ROOT / "config/config.yaml").read_text()), SCHEMA)


@pytest.fixture(scope="module")
def nr_and_schema():
    return _paper()["nr"], SCHEMA["properties"]["nr"]


def test_cells_and_the_bursts_they_share(nr_and_schema):
    nr, schema = nr_and_schema
    cells = rm.cells(nr, schema)
    # M_T x data = 16, the conditions' windows x data = 4, the sanity row, then the source
    # receiver's template x selection less the default pair
    assert len(cells) == 4 * 4 + 2 * 2 + 1 + 3
    assert list(cells)[16:21] == [
        "win2000_others_random",
        "win2000_none",
        "win1000_others_random",
        "win1000_none",
        rm.SINGLE_CELL,
    ]
    # the sanity row: the main run's settings, the nearest RRH alone in range, no data
    single = cells[rm.SINGLE_CELL]
    assert single["radio"]["range_m"] == pytest.approx(np.hypot(250.0, 15.0))
    assert single["traffic"]["data_beam"] == "none" and single["antenna"]["rrh_elements"] == 32
    assert single["receiver"] == cells["mt32_none"]["receiver"]
    assert rm.burst_owner(rm.SINGLE_CELL, cells, nr) == rm.SINGLE_CELL
    assert rm.cell_receivers(rm.SINGLE_CELL, nr) == ["source", "source_gated", "robust"]
    assert rm.CELL_KEY.match(f"nr.map.{rm.SINGLE_CELL}.source.claim.toa_p95")
    assert cells["win1000_none"]["receiver"]["search_range_m"] == 1000.0
    assert cells["win1000_none"]["traffic"] == cells["mt32_none"]["traffic"]
    assert cells["mt32_none"]["receiver"]["search_range_m"] is None
    # a window cell is its own burst owner: it reads the same channel through another window
    assert rm.burst_owner("win2000_others_random", cells, nr) == "win2000_others_random"
    assert rm.default_cell(nr) == "mt32_others_random"
    assert cells["mt8_all_train"]["antenna"]["rrh_elements"] == 8
    assert cells["mt8_all_train"]["traffic"]["data_beam"] == "train"
    assert cells["mt64_serving_only"]["traffic"]["load"] == 0.0
    # the default cell and the selection-only cell read the main run's bursts
    assert rm.burst_owner("mt32_others_random", cells, nr) is None
    assert rm.burst_owner("tpl_pss_sss_sel_peak", cells, nr) is None
    # the SSS-template cells share one burst set; their selection is the tracker's
    assert rm.burst_owner("tpl_sss_sel_peak", cells, nr) == rm.burst_owner("tpl_sss_sel_ss_rsrp", cells, nr)
    assert rm.calibration_owner("tpl_pss_sss_sel_peak", cells) == "mt32_others_random"
    assert rm.burst_owner("mt16_none", cells, nr) == "mt16_none"
    assert rm.cell_receivers("tpl_sss_sel_peak", nr) == ["source"]
    assert rm.cell_receivers("mt16_none", nr) == ["source", "source_gated", "robust"]
    assert rm.cell_receivers("win1000_none", nr) == ["source", "source_gated"]
    assert rm.receivers(nr) == {"source": False, "source_gated": True, "robust": True}
    assert [rm.receiver_of(t) for t in rm.receivers(nr)] == ["source", "source", "robust"]


def test_calibration_run_spans_the_segment_accelerations(nr_and_schema):
    nr, _ = nr_and_schema
    c = nr["map"]["calibration"]
    tr = Trajectory(tuple(map(tuple, c["phases"])), nr["trajectory"]["dt_s"], v0_m_s=c["v0_m_s"])
    assert tr.n_epochs >= c["epochs"]
    _, v, a = tr.state(tr.times_s())
    assert v[0] == c["v0_m_s"] and np.all(np.diff(v) >= 0)
    assert set(np.round(a, 6)) == {0.5, 0.0, 0.2}
    # the main run's speeds over the segment contain the calibration run's
    main = Trajectory(tuple(map(tuple, nr["trajectory"]["phases"])), nr["trajectory"]["dt_s"])
    first, end = nr["map"]["segment"]
    _, vs, acc = main.state(main.times_s()[first:end])
    assert vs.min() <= v.min() and v.max() <= vs.max() and vs.max() >= 300 / 3.6
    assert np.any(np.diff(acc) != 0)


def test_block_bootstrap_draws_whole_blocks():
    idx = rm.block_indices(make_rng(1, (0,)), 103, 10, 50)
    assert idx.shape == (50, 103)
    assert idx.min() >= 0 and idx.max() < 103
    # each block of 10 is consecutive epochs
    blocks = idx[:, :100].reshape(50, 10, 10)
    assert np.all(np.diff(blocks, axis=2) == 1)
    with pytest.raises(ValueError, match="block"):
        rm.block_indices(make_rng(1, (0,)), 5, 10, 50)
    with pytest.raises(ValueError, match="n_boot"):
        rm.block_indices(make_rng(1, (0,)), 50, 10, 0)


def test_claim_rule():
    low = rm.CLAIMS["toa_p95"]  # < 1.6 m
    assert rm.status(low, 1.0, 1.5, False) == rm.HOLDS
    assert rm.status(low, 1.7, 2.0, False) == rm.FAILS
    assert rm.status(low, 1.5, 1.7, False) == rm.UNRESOLVED
    assert rm.status(low, 1.0, 1.5, True) == rm.FAILS  # a lost tracker fails
    high = rm.CLAIMS["submeter"]  # ≈ 75 %, higher is better
    assert rm.status(high, 0.8, 0.9, False) == rm.HOLDS
    assert rm.status(high, 0.5, 0.7, False) == rm.FAILS
    assert rm.status(high, 0.7, 0.8, False) == rm.UNRESOLVED
    assert rm.status(high, None, None, False) == rm.UNRESOLVED
    rank = rm.CLAIMS["toa_beats_aod"]
    assert rm.status(rank, -2.0, -0.1, False) == rm.HOLDS
    assert rm.status(rank, 0.0, 0.0, False) == rm.FAILS  # both lost alike: no ranking
    assert rm.status(rank, -0.1, 0.2, False) == rm.UNRESOLVED


def _errors(n, rng, scale_toa=0.3, scale_aod=2.0, fused=0.2):
    aod = np.radians(rng.normal(0, 0.5, (n, 3)))
    rngm = rng.normal(0, 0.5, (n, 3))
    return (
        aod,
        rngm,
        {
            "aod": np.abs(rng.normal(0, scale_aod, n)),
            "toa": np.abs(rng.normal(0, scale_toa, n)),
            "aod_toa": np.abs(rng.normal(0, fused, n)),
        },
    )


def test_cell_key_numbers_mark_what_holds_and_what_is_lost():
    rng = np.random.default_rng(3)
    aod, rngm, pos = _errors(600, rng)
    nums = rm.cell_key_numbers("c", "source", aod, rngm, pos, 500.0, make_rng(1, (0,)), 50, 400, 0.95, "test")
    p = "nr.map.c.source"
    for metric in rm.METRICS:
        e, lo, hi = (nums[f"{p}.{metric}{s}"]["value"] for s in ("", ".lo", ".hi"))
        assert lo <= e <= hi, metric
    assert nums[f"{p}.claim.aod_p95"]["value"] == rm.HOLDS  # |N(0, 0.5°)| p95 ≈ 0.98° < 1.3°
    assert nums[f"{p}.claim.toa_p95"]["value"] == rm.HOLDS  # 0.98 m < 1.6 m
    assert nums[f"{p}.claim.ekf_mean"]["value"] == rm.HOLDS  # 0.16 m
    assert nums[f"{p}.claim.toa_beats_aod"]["value"] == rm.HOLDS
    assert nums[f"{p}.claim.fusion_best"]["value"] == rm.HOLDS
    # the fused tracker lost on 5 % of the epochs: no accuracy, its claims fail
    pos["aod_toa"][::20] = 1e6  # spread along the run: every resample holds about 5 %
    nums = rm.cell_key_numbers("c", "source", aod, rngm, pos, 500.0, make_rng(1, (0,)), 50, 400, 0.95, "test")
    assert nums[f"{p}.track.aod_toa.lost_frac"]["value"] == pytest.approx(0.05)
    assert nums[f"{p}.track.aod_toa.err_m.mean"]["value"] is None
    assert nums[f"{p}.track.aod_toa.err_m.mean"]["lost_frac"] == pytest.approx(0.05)
    for c in ("ekf_mean", "ekf_p95", "ekf_p99", "submeter"):
        assert nums[f"{p}.claim.{c}"]["value"] == rm.FAILS
    # clipped at 250 m, 5 % lost epochs add 12.5 m: fusion no longer best
    assert nums[f"{p}.claim.fusion_best"]["value"] == rm.FAILS
    assert all(e["value"] is None or abs(e["value"]) < 1e4 for e in nums.values())


def test_summary_counts_cells(nr_and_schema):
    nr, _ = nr_and_schema
    nums = {}
    rng = np.random.default_rng(4)
    cells = ["mt32_others_random", "tpl_sss_sel_peak"]
    for c in cells:
        for rx in rm.cell_receivers(c, nr):
            nums |= rm.cell_key_numbers(c, rx, *_errors(300, rng), 500.0, make_rng(1, (0,)), 50, 100, 0.95, "t")
    # the sanity row is another deployment: the summary counts leave it out
    for rx in rm.cell_receivers(rm.SINGLE_CELL, nr):
        nums |= rm.cell_key_numbers(
            rm.SINGLE_CELL, rx, *_errors(300, rng), 500.0, make_rng(1, (0,)), 50, 100, 0.95, "t"
        )
    s = rm.summary_key_numbers(nums, [*cells, rm.SINGLE_CELL], nr)
    assert s["nr.map.source.n_cells"]["value"] == 2 and s["nr.map.robust.n_cells"]["value"] == 1
    for rx in ("source", "robust"):
        for c in rm.CLAIMS:
            assert (
                sum(s[f"nr.map.{rx}.{c}.n_{w}"]["value"] for w in ("holds", "fails", "unresolved"))
                == s[f"nr.map.{rx}.n_cells"]["value"]
            )


def test_config_checks_name_the_map_keys():
    cfg = _paper()
    cfg["nr"]["map"]["segment"] = [1500, 9000]
    cfg["nr"]["map"]["rrh_elements"] = [8, 16]
    with pytest.raises(ConfigError) as exc:
        check_config(cfg, SCHEMA)
    assert "nr.map.segment" in str(exc.value) and "nr.map.rrh_elements" in str(exc.value)
    cfg = _paper()
    cfg["nr"]["map"]["block_epochs"] = 5000
    with pytest.raises(ConfigError, match="nr.map.block_epochs"):
        check_config(cfg, SCHEMA)


def test_diagnostics_split_endfire_from_broadside():
    aod_true = np.radians(np.array([[1.0, 90.0, 178.5]] * 4))  # 1 and 1.5 deg from the track
    err = np.radians(np.array([[2.0, 0.1, 3.0]] * 4))
    n_det = np.array([[5, 3, 7]] * 4)
    d = md.diagnostic_key_numbers("c", "source", err, aod_true, n_det, "t")
    p = "nr.map.c.source.diag"
    assert d[f"{p}.aod_err_deg.median_endfire"]["value"] == pytest.approx(2.5)
    assert d[f"{p}.aod_err_deg.median_broadside"]["value"] == pytest.approx(0.1)
    assert d[f"{p}.frac_endfire"]["value"] == pytest.approx(2 / 3)
    assert d[f"{p}.n_detected.median"]["value"] == 5


def test_endfire_bias_per_true_angle_bin():
    rng = make_rng(3, (1,))
    n = 400
    # true azimuths in (-pi, 0): half ahead (theta near 0), half behind (near -pi)
    psi = np.radians(rng.uniform(0.0, 8.0, n))
    ahead = rng.random(n) < 0.5
    theta = np.where(ahead, -psi, -np.pi + psi)
    toward = np.where(ahead, -1.0, 1.0)  # broadside (-pi/2) lies at smaller theta ahead
    bias = np.where(np.degrees(psi) < 2.0, 1.5, 0.2)  # deg toward broadside
    err = np.radians(bias * toward + rng.normal(0.0, 0.1, n))
    d = md.endfire_bias_key_numbers("c", "robust", err.reshape(-1, 2), theta.reshape(-1, 2), (1.0, 2.0, 5.0), "t")
    p = "nr.map.c.robust.diag"
    assert d[f"{p}.aod_bias_deg.b0"]["value"] == pytest.approx(1.5, abs=0.05)
    assert d[f"{p}.aod_bias_deg.b1"]["value"] == pytest.approx(1.5, abs=0.05)
    assert d[f"{p}.aod_bias_deg.b2"]["value"] == pytest.approx(0.2, abs=0.05)
    assert d[f"{p}.aod_bias_deg.b3"]["value"] == pytest.approx(0.2, abs=0.05)
    assert sum(d[f"{p}.aod_n.b{i}"]["value"] for i in range(4)) == n
    few = md.endfire_bias_key_numbers("c", "robust", err[:10], theta[:10], (1.0, 2.0, 5.0), "t")
    assert all(few[f"{p}.aod_bias_deg.b{i}"]["value"] is None for i in range(4))
    with pytest.raises(ValueError, match="shape"):
        md.endfire_bias_key_numbers("c", "robust", err, theta[:-1], (1.0, 2.0, 5.0), "t")


def test_calibration_diag_names_each_trackers_q():
    cal = {"robust/aod": {"q": 0.1}, "robust/aod_toa": {"q": 1000.0}, "source/aod_toa": {"q": 3.0}}
    d = md.calibration_diag_key_numbers("c", "robust", cal, "t")
    assert d == {
        "nr.map.c.robust.diag.q.aod": d["nr.map.c.robust.diag.q.aod"],
        "nr.map.c.robust.diag.q.aod_toa": d["nr.map.c.robust.diag.q.aod_toa"],
    }
    assert d["nr.map.c.robust.diag.q.aod_toa"]["value"] == 1000.0


def test_along_cross_split_and_loss():
    along = np.array([0.3, -0.4, 0.0, 0.6])
    cross = np.array([0.4, 0.3, 1.0, 0.8])
    d = md.along_cross_key_numbers("c", "robust", along, np.hypot(along, cross), 500.0, "t")
    p = "nr.map.c.robust.diag.track.aod_toa"
    assert d[f"{p}.along_m.mean"]["value"] == pytest.approx(np.mean(np.abs(along)))
    assert d[f"{p}.cross_m.mean"]["value"] == pytest.approx(np.mean(cross))
    lost = md.along_cross_key_numbers("c", "robust", along, np.array([0.5, 0.5, 0.5, 400.0]), 500.0, "t")
    assert lost[f"{p}.along_m.mean"]["value"] is None
    assert lost[f"{p}.along_m.mean"]["lost_frac"] == pytest.approx(0.25)


def test_shard_paths_reuse_the_main_run_and_other_cells(nr_and_schema):
    nr, schema = nr_and_schema
    cells = rm.cells(nr, schema)
    n_main = 5775
    # segment 1500..2499 lies in the main run's second of four shards
    assert rm.shard_paths("mt32_others_random", "r0", cells, nr, n_main) == ["results/nr/estimates/r0/s1.nc"]
    assert rm.shard_paths("tpl_sss_sel_ss_rsrp", "r0", cells, nr, n_main) == [
        f"results/nr/map/tpl_sss_sel_peak/estimates/r0/s{k}.nc" for k in range(nr["map"]["n_shards"])
    ]
    assert rm.shard_paths("tpl_pss_sss_sel_peak", "cal", cells, nr, n_main) == [
        "results/nr/map/mt32_others_random/estimates/cal/s0.nc"
    ]


def test_single_rrh_range_leaves_the_nearest_rrh_alone():
    """Along the whole track exactly one RRH lies within the sanity row's range, except at the
    midpoint between two, where both lie on its edge."""
    dep = {"spacing_m": 500.0, "offset_m": 15.0}
    r = rm.single_rrh_range_m(dep)
    rrh_x = np.arange(0.0, 5001.0, 500.0)
    x = np.r_[np.linspace(0.3, 4999.7, 20001), np.arange(250.0, 4750.0, 500.0) - 0.01]
    d2d = np.hypot(x[:, None] - rrh_x[None, :], dep["offset_m"])
    assert np.all((d2d <= r).sum(axis=1) == 1)
    mid = np.hypot(250.0 - rrh_x[:2], dep["offset_m"])
    assert np.all(mid <= r) and np.all(mid >= r - 1e-9)


def test_sanity_row_off():
    cfg = _paper()
    cfg["nr"]["map"]["conditions"]["single_rrh"] = False
    cells = rm.cells(cfg["nr"], SCHEMA["properties"]["nr"])
    assert rm.SINGLE_CELL not in cells and len(cells) == 4 * 4 + 2 * 2 + 3


def test_nearest_rrh_errors_follow_the_truth_not_the_selection():
    import xarray as xr

    from railradio.constants import SPEED_OF_LIGHT_M_S

    rrh_x = np.array([0.0, 500.0, 1000.0])
    x = np.array([10.0, 260.0, 740.0, 990.0])  # nearest: 0, 1, 1, 2
    rrh = np.array([[0, 1], [0, 1], [2, 0], [1, 2]])  # epoch 2: RRH 1 not a candidate
    aod_true = np.zeros((4, 2))
    toa_true = np.full((4, 2), 1e-6)
    aod_hat = aod_true + np.array([[0.01, 0.5], [0.5, 0.02], [0.5, 0.5], [0.5, np.nan]])
    toa_hat = toa_true + np.array([[1e-9, 0.0], [0.0, -2e-9], [0.0, 0.0], [0.0, 1e-9]])
    dims = ("epoch", "cand")
    ds = xr.Dataset(
        {
            "rrh": (dims, rrh),
            "aod_hat": (dims, aod_hat),
            "aod_true": (dims, aod_true),
            "toa_hat": (dims, toa_hat),
            "toa_true": (dims, toa_true),
            "x_true": (("epoch",), x),
        }
    )
    aod, rng = md.nearest_errors(ds, rrh_x)
    np.testing.assert_allclose(aod[:2], [0.01, 0.02])
    np.testing.assert_allclose(rng[:2], [1e-9 * SPEED_OF_LIGHT_M_S, -2e-9 * SPEED_OF_LIGHT_M_S])
    assert np.isnan(aod[2]) and np.isnan(rng[2])  # not among the candidates
    assert np.isnan(aod[3])  # a candidate, but its AOD not measured
    idx = np.tile(np.arange(4), (5, 1))  # every resample the sample itself
    k = md.nearest_key_numbers("c", "source", aod, rng, idx, 0.95, "t")
    p = "nr.map.c.source.diag.nearest"
    assert k[f"{p}.measured_frac"]["value"] == pytest.approx(0.5)
    p95 = np.percentile(np.degrees([0.01, 0.02]), 95)
    assert k[f"{p}.meas.aod_err_deg.p95"]["value"] == pytest.approx(p95)
    assert (
        k[f"{p}.meas.aod_err_deg.p95.lo"]["value"] == pytest.approx(p95) == k[f"{p}.meas.aod_err_deg.p95.hi"]["value"]
    )
    # 1.15 deg and 0.6 m: within the source's 1.3 deg and 1.6 m
    assert k[f"{p}.claim.aod_p95"]["value"] == rm.HOLDS and k[f"{p}.claim.toa_p95"]["value"] == rm.HOLDS
    far = md.nearest_key_numbers("c", "source", aod * 10, rng * 10, idx, 0.95, "t")
    assert far[f"{p}.claim.aod_p95"]["value"] == rm.FAILS and far[f"{p}.claim.toa_p95"]["value"] == rm.FAILS
    never = md.nearest_key_numbers("c", "source", np.full(4, np.nan), np.full(4, np.nan), idx, 0.95, "t")
    assert never[f"{p}.meas.toa_err_m.p95"]["value"] is None and never[f"{p}.measured_frac"]["value"] == 0.0
    assert never[f"{p}.claim.toa_p95"]["value"] == rm.UNRESOLVED
    with pytest.raises(ValueError, match="aod_err_rad"):
        md.nearest_key_numbers("c", "source", aod, rng[:-1], idx, 0.95, "t")
    with pytest.raises(ValueError, match="idx"):
        md.nearest_key_numbers("c", "source", aod, rng, idx[:, :3], 0.95, "t")


def test_off_air_selections_name_the_pss_lock():
    import xarray as xr

    from railradio.constants import SPEED_OF_LIGHT_M_S

    rrh_x = np.arange(0.0, 2001.0, 500.0)  # N_ID2 = k mod 3: 0 1 2 0 1
    n_id2 = np.arange(rrh_x.size) % 3
    x = np.array([1480.0, 1510.0])  # nearest RRH 3 (N_ID2 0), alone within 260 m
    rrh = np.array([[3, 0, 2], [3, 4, 0]])
    t3 = np.hypot(20.0, 15.0) / SPEED_OF_LIGHT_M_S
    toa_true = np.full((2, 3), 1e-6)
    toa_true[:, 0] = t3
    toa_hat = np.array([[t3, t3 + 5.0 / SPEED_OF_LIGHT_M_S, 2e-6], [t3, 3e-6, t3 + 50.0 / SPEED_OF_LIGHT_M_S]])
    dims = ("epoch", "cand")
    ds = xr.Dataset(
        {"rrh": (dims, rrh), "toa_hat": (dims, toa_hat), "toa_true": (dims, toa_true), "x_true": (("epoch",), x)}
    )
    order = np.tile(np.arange(3), (2, 1))
    ok = np.array([[True, True, True], [True, True, False]])
    off, pss, locked = md.off_air_selections(ds, order, ok, rrh_x, 15.0, 260.0, n_id2)
    np.testing.assert_array_equal(off, [[False, True, True], [False, True, False]])
    # RRH 0 shares RRH 3's N_ID2 and sits at its delay (5 m); RRH 2 and 4 do not
    np.testing.assert_array_equal(pss, [[False, True, False], [False, False, False]])
    np.testing.assert_array_equal(locked, [[False, True, False], [False, False, False]])
    k = md.off_air_key_numbers("c", "source", ok, off, pss, locked, "t")
    p = "nr.map.c.source.diag.off_air"
    assert k[f"{p}.frac"]["value"] == pytest.approx(3 / 5)
    assert k[f"{p}.pss_frac"]["value"] == pytest.approx(1 / 3) == k[f"{p}.locked_frac"]["value"]
    none = md.off_air_key_numbers("c", "source", ok, off & False, pss & False, locked & False, "t")
    assert none[f"{p}.frac"]["value"] == 0.0 and none[f"{p}.pss_frac"]["value"] is None
    with pytest.raises(ValueError, match="share a shape"):
        md.off_air_key_numbers("c", "source", ok, off[:1], pss, locked, "t")


def test_the_link_budget_puts_one_rrh_in_the_sanity_rows_range(nr_and_schema):
    """The link code itself (not a copy of its rule) synthesizes one RRH along the sanity
    row's track, two at the midpoint between RRHs (on the range's edge)."""
    from railradio.nr.channel.link import ShadowingMap, link_budget
    from railradio.nr.engine.simulate import scenario_from_config

    nr, schema = nr_and_schema
    scn = scenario_from_config(rm.cells(nr, schema)[rm.SINGLE_CELL])
    dep = scn.deployment
    shadow = ShadowingMap(1, (0,), dep, scn.radio)
    x_mid = float(dep.x_m[10] + dep.x_m[11]) / 2
    for x in (float(dep.x_m[10]), float(dep.x_m[10]) + 100.0, x_mid - 0.5, x_mid + 0.5, float(dep.x_m[11]) - 249.0):
        lb = link_budget(x, 80.0, dep, scn.radio, scn.rrh_array, scn.train_array, shadow, False)
        assert lb.rrh.size == 1, (x, lb.rrh)
    lb = link_budget(x_mid, 80.0, dep, scn.radio, scn.rrh_array, scn.train_array, shadow, False)
    assert sorted(lb.rrh.tolist()) == [10, 11]


def test_the_sanity_rows_helpers_name_their_bad_input():
    with pytest.raises(ValueError, match="spacing_m"):
        rm.single_rrh_range_m({"spacing_m": 0.0, "offset_m": 15.0})
    with pytest.raises(ValueError, match="offset_m"):
        rm.single_rrh_range_m({"spacing_m": 500.0, "offset_m": -1.0})
    import xarray as xr

    ds = xr.Dataset(
        {
            "rrh": (("epoch", "cand"), np.zeros((2, 2), int)),
            "toa_hat": (("epoch", "cand"), np.zeros((2, 2))),
            "toa_true": (("epoch", "cand"), np.zeros((2, 2))),
            "aod_hat": (("epoch", "cand"), np.zeros((2, 2))),
            "aod_true": (("epoch", "cand"), np.zeros((2, 2))),
            "x_true": (("epoch",), np.zeros(2)),
        }
    )
    with pytest.raises(ValueError, match="rrh_x_m"):
        md.nearest_errors(ds, np.zeros(0))
    order, ok = np.zeros((2, 2), int), np.ones((2, 2), bool)
    with pytest.raises(ValueError, match="order and ok"):
        md.off_air_selections(ds, order, ok[:1], np.zeros(3), 15.0, 250.0, np.zeros(3, int))
    with pytest.raises(ValueError, match="n_id2"):
        md.off_air_selections(ds, order, ok, np.zeros(3), 15.0, 250.0, np.zeros(2, int))
    with pytest.raises(ValueError, match="range_m"):
        md.off_air_selections(ds, order, ok, np.zeros(3), 15.0, 0.0, np.zeros(3, int))
    with pytest.raises(ValueError, match="confidence"):
        md.nearest_key_numbers("c", "source", np.zeros(2), np.zeros(2), np.zeros((3, 2), int), 1.0, "t")


def test_a_resample_without_a_measurement_leaves_the_claim_unresolved():
    aod = np.array([0.001, np.nan, np.nan, np.nan])
    rng = np.array([0.1, np.nan, np.nan, np.nan])
    idx = np.array([[0, 1, 2, 3], [1, 2, 3, 1]])  # the second resample never sees epoch 0
    k = md.nearest_key_numbers("c", "source", aod, rng, idx, 0.95, "t")
    p = "nr.map.c.source.diag.nearest"
    assert k[f"{p}.meas.toa_err_m.p95"]["value"] == pytest.approx(0.1)
    assert k[f"{p}.meas.toa_err_m.p95.lo"]["value"] is None
    assert k[f"{p}.claim.toa_p95"]["value"] == rm.UNRESOLVED
