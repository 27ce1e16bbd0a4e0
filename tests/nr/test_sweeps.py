"""The nr sensitivity sweeps (docs/model/nr.md §9): clock-synchronization errors on the measured TOAs,
their TOA floor, per-case epochs in the sensitivity key numbers, sparse RRHs at the track's
start, fewer SS beams."""

import json

import numpy as np
import pytest
import xarray as xr

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.channel.clocks import apply_clock_errors, clock_offsets_s
from railradio.nr.study.keys import sensitivity_floor_numbers, sensitivity_key_numbers, toa_floor_m
from railradio.nr.waveform.numerology import SAMPLE_RATE_HZ
from railradio.rng import spawn_key


def _estimates(rrh: np.ndarray, n_rx: int = 2) -> xr.Dataset:
    n_e, n_c = rrh.shape
    toa = np.arange(n_e * n_c, dtype=float).reshape(n_e, n_c) * 1e-7
    return xr.Dataset(
        {
            "toa_hat": (
                ("receiver", "epoch", "cand"),
                np.broadcast_to(toa, (n_rx, n_e, n_c)).copy(),
                {"units": "s", "long_name": "TOA"},
            ),
            "rrh": (("epoch", "cand"), rrh),
        }
    )


def test_clock_offsets_are_per_rrh_and_realization():
    key0, key1 = spawn_key("nr", 0), spawn_key("nr", 1000)
    rrh = np.array([[3, 4, 5], [4, 5, 6]])
    a = clock_offsets_s(7, key0, rrh, 1e-9)
    # one offset per RRH, the same wherever (and in whichever shard) it appears
    assert a[0, 1] == a[1, 0] and a[0, 2] == a[1, 1]
    assert np.all(clock_offsets_s(7, key0, np.array([6, 3]), 1e-9) == [a[1, 2], a[0, 0]])
    # the calibration run draws its own offsets
    assert np.all(np.abs(clock_offsets_s(7, key1, rrh, 1e-9) - a) > 1e-13)
    assert np.all(clock_offsets_s(7, key0, rrh, 0.0) == 0)
    with pytest.raises(ValueError, match="rrh_sigma_s"):
        clock_offsets_s(7, key0, rrh, -1e-9)


def test_clock_offsets_have_the_configured_spread():
    """Over many RRHs the offsets are N(0, σ²): sample std within 3 standard errors."""
    off = clock_offsets_s(1, spawn_key("nr", 0), np.arange(4000), 3e-9)
    assert abs(off.mean()) < 3 * 3e-9 / np.sqrt(4000)
    assert abs(off.std(ddof=1) / 3e-9 - 1) < 3 / np.sqrt(2 * 4000)


def test_apply_clock_errors_shifts_every_receivers_toa_by_rrh_offset_plus_bias():
    rrh = np.array([[0, 1, 2], [1, 2, 3]])
    ds = _estimates(rrh)
    key = spawn_key("nr", 0)
    assert apply_clock_errors(ds, 3, key) is ds  # zero errors: the estimates unchanged
    out = apply_clock_errors(ds, 3, key, rrh_sigma_s=2e-9, train_bias_s=5e-9)
    shift = out["toa_hat"].values - ds["toa_hat"].values
    np.testing.assert_allclose(shift[0], clock_offsets_s(3, key, rrh, 2e-9) + 5e-9, rtol=0, atol=1e-20)
    np.testing.assert_array_equal(shift[0], shift[1])
    assert out["toa_hat"].dims == ds["toa_hat"].dims and out["toa_hat"].attrs["units"] == "s"
    assert np.all(ds["toa_hat"].values == _estimates(rrh)["toa_hat"].values)  # input untouched
    with pytest.raises(ValueError, match="train_bias_s"):
        apply_clock_errors(ds, 3, key, train_bias_s=np.inf)


def test_toa_floor_against_monte_carlo():
    """Quantiles of |U(±c/2F_s) + c·δ| by quadrature against a large Monte Carlo sample."""
    half = SPEED_OF_LIGHT_M_S / SAMPLE_RATE_HZ / 2
    assert toa_floor_m(0.0) == pytest.approx(0.5 * half)
    assert toa_floor_m(0.0, q=0.95) == pytest.approx(0.95 * half)
    rng = np.random.default_rng(5)
    for sigma in (1e-9, 3e-9, 1e-8):
        e = np.abs(rng.uniform(-half, half, 400_000) + SPEED_OF_LIGHT_M_S * sigma * rng.standard_normal(400_000))
        for q in (0.5, 0.95):
            assert toa_floor_m(sigma, q) == pytest.approx(np.quantile(e, q), rel=0.01)
    # large σ: the Gaussian's 0.674 σ (median) and 1.96 σ (p95) dominate
    assert toa_floor_m(1e-7) == pytest.approx(0.6745 * SPEED_OF_LIGHT_M_S * 1e-7, rel=0.01)
    assert toa_floor_m(1e-7, 0.95) == pytest.approx(1.96 * SPEED_OF_LIGHT_M_S * 1e-7, rel=0.01)
    k = sensitivity_floor_numbers({"base": 0.0, "sync_3ns": 3e-9})
    assert k["sens.nr.base.bound.toa_floor_m.median"]["value"] == pytest.approx(0.5 * half)
    assert k["sens.nr.sync_3ns.bound.toa_floor_m.median"]["value"] == pytest.approx(toa_floor_m(3e-9))


def _track(n: int, err: float) -> xr.Dataset:
    rx, var = ["source", "robust"], ["aod", "toa", "aod_toa"]
    pos = np.full((2, 3, 2, n), err)
    pos[..., n // 2 :] = 10 * err  # the later half is worse: the epoch cut shows
    return xr.Dataset(
        {
            "pos_err": (("receiver", "measurements", "gate", "epoch"), pos),
            "along_err": (("receiver", "measurements", "gate", "epoch"), -0.6 * pos),  # cross: 0.8 pos
            "aod_err": (("receiver", "epoch", "slot"), np.full((2, n, 3), 0.01)),
            "range_err": (("receiver", "epoch", "slot"), np.full((2, n, 3), 0.4)),
            "t": (("epoch",), np.arange(n) * 0.1),
        },
        coords={"receiver": rx, "measurements": var, "gate": [0, 1]},
        attrs={"config_json": json.dumps({"sim": {"deployment": {"spacing_m": 500.0}}})},
    )


def test_sensitivity_key_numbers_cut_each_case_to_its_epochs():
    base, short = _track(400, 1.0), _track(400, 2.0)
    k = sensitivity_key_numbers(base, {"short": short}, {"base": 400, "short": 200})
    # base: epochs 50..399, half at 1 and half at 10 m; short: epochs 50..199 at 2 m
    assert k["sens.nr.base.robust.track.aod_toa_gated.err_m.mean"]["value"] == pytest.approx((150 * 1 + 200 * 10) / 350)
    p = "sens.nr.short.robust.track.aod_toa_gated"
    assert k[f"{p}.along_m.mean"]["value"] == pytest.approx(0.6 * 2.0)
    assert k[f"{p}.cross_m.mean"]["value"] == pytest.approx(0.8 * 2.0)
    assert k["sens.nr.short.robust.track.aod_toa_gated.err_m.mean"]["value"] == pytest.approx(2.0)
    assert "first 200 epochs" in k["sens.nr.short.source.meas.toa_err_m.p95"]["description"]
    with pytest.raises(ValueError, match="fewer than n_epochs"):
        sensitivity_key_numbers(base, {"short": _track(100, 2.0)}, {"base": 400, "short": 200})


def test_sparse_rrhs_at_the_track_start_give_geometric_truth():
    """1000 m spacing: at x = 0 only 5 RRHs lie within the 5 km range, the 6th candidate is
    not synthesized; its truth is the geometry, its received power NaN."""
    import yaml

    from railradio.config import deep_merge
    from railradio.nr.engine.epochs import simulate_epochs
    from railradio.nr.engine.simulate import scenario_from_config

    from ..conftest import ROOT

    nr = yaml.safe_load((ROOT / "config/config.yaml").read_text())["nr"]
    nr.pop("sensitivity")
    scn = scenario_from_config(deep_merge(nr, {"deployment": {"spacing_m": 1000.0}}))
    ds = simulate_epochs(scn, np.array([0]), 1, spawn_key("nr", 0))
    rrh = ds["rrh"].values[0]
    far = np.hypot(scn.deployment.x_m[rrh], scn.deployment.offset_m) > scn.radio.range_m
    assert far.sum() == 1  # the RRH at 5000 m is 5000.02 m away
    assert np.isnan(ds["rx_power"].values[0, far]).all() and np.isfinite(ds["rx_power"].values[0, ~far]).all()
    expect = np.sqrt(
        scn.deployment.x_m[rrh] ** 2 + scn.deployment.offset_m**2 + (scn.deployment.h_bs_m - scn.deployment.h_ut_m) ** 2
    )
    np.testing.assert_allclose(ds["d3d"].values[0], expect, rtol=1e-9)


def _cases_cfg():
    import yaml

    from railradio.config import deep_merge

    from ..conftest import ROOT

    nr = yaml.safe_load((ROOT / "config/config.yaml").read_text())["nr"]
    sens = nr.pop("sensitivity")
    return nr, sens, {c: deep_merge(nr, o) for c, o in sens["cases"].items()}


def test_case_scheduling_reuses_bursts_and_cuts_epochs():
    from railradio.nr.study import cases as nc

    nr, sens, cases = _cases_cfg()
    n_main = 5775
    from railradio.nr.engine.epochs import shard_epochs

    s0 = shard_epochs(n_main, nr["n_shards"], 0).size  # epochs of the main run's first shard
    assert s0 >= 400
    # the sweep reference: the main run's bursts, cut to its epochs (all in shard 0)
    assert nc.case_epochs(cases["sweep_ref"], sens) == 400
    assert nc.case_cal_epochs(cases["sweep_ref"], nr) == 250
    assert nc.case_inputs("sweep_ref", cases, nr, sens, "r0", n_main, 2) == ["results/nr/estimates/r0/s0.nc"]
    longer = dict(cases["sweep_ref"], max_epochs=s0 + 1)
    assert nc.case_inputs("x", {"x": longer}, nr, sens, "r0", n_main, 2) == [
        "results/nr/estimates/r0/s0.nc",
        "results/nr/estimates/r0/s1.nc",
    ]
    assert nc.case_inputs("sweep_ref", cases, nr, sens, "cal", n_main, 2) == ["results/nr/estimates/cal/s0.nc"]
    # a clock-error case changes no burst: it reads the same shards
    assert nc.case_inputs("sync_3ns", cases, nr, sens, "r0", n_main, 2) == nc.case_inputs(
        "sweep_ref", cases, nr, sens, "r0", n_main, 2
    )
    # a full-length tracker-only case: the main shards covering 2500 epochs
    assert len(nc.case_inputs("w_distance", cases, nr, sens, "r0", n_main, 2)) == int(
        np.searchsorted(np.linspace(0, n_main, nr["n_shards"] + 1).round(), 2500)
    )
    # a simulated sweep point: its own shards, fewer for fewer epochs
    assert nc.case_inputs("tdl_a", cases, nr, sens, "r0", n_main, 2) == ["results/nr/cases/tdl_a/estimates/r0/s0.nc"]
    assert nc.case_inputs("tdl_a", cases, nr, sens, "cal", n_main, 2) == ["results/nr/cases/tdl_a/estimates/cal/s0.nc"]
    assert nc.case_epochs(cases["speed_500"], sens) == 1150
    # as many shards per epoch as a full-length case (rounded), at least one
    assert nc.case_n_shards(cases["speed_500"], nr, sens, "r0", 2) == max(
        1, round(sens["n_shards"] * 1150 / sens["epochs"])
    )
    assert nc.case_n_shards(cases["speed_500"], nr, dict(sens, n_shards=10), "r0", 2) == 5
    assert nc.case_n_shards(cases["load_half"], nr, sens, "r0", 2) == sens["n_shards"]
    # a case with an earlier case's bursts reads that case's shards
    assert nc.case_inputs("panels_200m_point", cases, nr, sens, "r0", n_main, 2)[0].startswith(
        "results/nr/cases/panels_200m/"
    )
    # the speed case reaches 500 km/h within its epochs
    from railradio.nr.engine.simulate import scenario_from_config

    traj = scenario_from_config(cases["speed_500"]).trajectory
    _, v, _ = traj.state(np.array([(nc.case_epochs(cases["speed_500"], sens) - 1) * traj.dt_s]))
    assert v[0] * 3.6 == pytest.approx(500.0, abs=0.1)


def test_fewer_ss_beams_keep_the_burst_pattern_prefix():
    """n_beams 32/16: the first 32/16 block positions of the source pattern, beams spread
    over the same 0..180 deg (the schema allows 2..64)."""
    from railradio.nr.channel.antenna import RrhArray
    from railradio.nr.receiver.config import ReceiverConfig
    from railradio.nr.waveform.numerology import ssb_first_symbols

    full = ssb_first_symbols("source", 64)
    for n in (32, 16):
        assert np.array_equal(ReceiverConfig(n_blocks=n).ssb_first, full[:n])
        ang = np.degrees(RrhArray(n_beams=n).beam_angles_rad)
        assert ang[0] == pytest.approx(-90.0 / n) and ang[-1] == pytest.approx(-180.0 + 90.0 / n)


@pytest.mark.parametrize("delay", [412.0, 1000.3, 2345.7])
@pytest.mark.parametrize("offset_ns", [1.0, 3.0, 10.0])
def test_clock_offset_on_the_toa_equals_a_shifted_burst_up_to_one_sample(delay, offset_ns):
    """The tracker-side shortcut of apply_clock_errors against the faithful model: a burst
    synthesized with the delay τ + δ gives the same integer-sample TOA as τ's TOA + δ up
    to one sample (noiseless, one LOS path, decimated receiver)."""
    from railradio.nr.channel.link import Links
    from railradio.nr.channel.tdl import TdlProfile
    from railradio.nr.receiver.config import ReceiverConfig
    from railradio.nr.receiver.correlator import Correlator
    from railradio.nr.synthesis.synthesizer import Synthesizer
    from railradio.nr.waveform.ssb import qpsk_pool

    los = TdlProfile("LOS", 1.0, 0.0, np.zeros(0), np.zeros(0))
    cfg = ReceiverConfig(decimation=4, n_blocks=8)
    rng = np.random.default_rng(11)
    syn = Synthesizer(cfg, los, qpsk_pool(rng, 16))
    cor = Correlator(cfg)

    def toa_samples(tau_samples):
        links = Links(
            n_id1=np.array([5]),
            n_id2=np.array([1]),
            tau_s=np.array([tau_samples]) / SAMPLE_RATE_HZ,
            amp=np.ones(1),
            beam_amp=np.ones((1, 64)),
            data_amp=np.ones(1),
            f_los_hz=np.zeros(1),
            phase0=np.zeros(1),
            doppler_hz=0.0,
            noise_psd_w_hz=0.0,
        )
        z, s_min = syn(links, np.random.default_rng(3), noise=False)
        return cor.correlate(z, s_min, np.array([5]), np.array([1])).toa_samples[0]

    d = offset_ns * 1e-9 * SAMPLE_RATE_HZ
    faithful = toa_samples(delay + d)
    shortcut = toa_samples(delay) + d
    assert abs(faithful - shortcut) <= 1.0
    assert abs(faithful - (delay + d)) <= 0.5  # both within the integer-sample quantization
