"""Per-epoch simulation of the nr study: channel, received burst, per-cell estimates.

One call of :func:`simulate_epochs` handles any set of epochs (a shard of the track); every
random draw is keyed by (realization, epoch) or (realization, RRH), so the result of an
epoch does not depend on the shard it falls in.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import xarray as xr

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.antenna import RrhArray, TrainArray
from railradio.nr.channel import tdl_profile
from railradio.nr.geometry import Deployment, Trajectory
from railradio.nr.link import RadioParams, ShadowingMap, link_budget
from railradio.nr.numerology import SAMPLE_RATE_HZ
from railradio.nr.receiver import Correlator, ReceiverConfig, Synthesizer
from railradio.nr.ssb import qpsk_pool
from railradio.rng import make_rng

# sub-keys below the realization's spawn key
KEY_SHADOWING, KEY_POOL, KEY_EPOCH = 1, 2, 3


@dataclass(frozen=True)
class Scenario:
    """Everything that defines one realization of the nr study (SI units)."""

    trajectory: Trajectory
    deployment: Deployment = field(default_factory=Deployment)
    radio: RadioParams = field(default_factory=RadioParams)
    rrh_array: RrhArray = field(default_factory=RrhArray)
    train_array: TrainArray = field(default_factory=TrainArray)
    receiver: ReceiverConfig = field(default_factory=ReceiverConfig)
    tdl: str = "TDL-D"
    delay_spread_s: float = 20e-9
    detector: str = "seed"
    pfa: float = 1e-3
    variants: tuple = ()
    """Extra receivers run on the same bursts: ((name, ReceiverConfig, detector), ...);
    they must share the decimation and SS-block pattern of ``receiver``."""
    n_candidates: int = 6
    full_channel_range_m: float = 1500.0
    n_sinusoids: int = 16
    pool_size: int = 256
    shadowing: bool = True
    data_beam: str = "train"
    """Beam of the data symbols: train | random | none (:class:`Synthesizer`)."""

    @cached_property
    def profile(self):
        return tdl_profile(self.tdl, self.delay_spread_s)


def simulate_epochs(scn: Scenario, epochs: np.ndarray, seed: int, key: tuple[int, ...],
                    keep_corr_epochs: tuple[int, ...] = ()) -> xr.Dataset:
    """Simulate the given epochs of one realization.

    Parameters
    ----------
    scn
        The scenario.
    epochs
        Epoch indices (t = epoch · dt).
    seed, key
        Config seed and the realization's spawn key.
    keep_corr_epochs
        Epochs whose per-block correlation functions are kept (for inspection).

    Returns
    -------
    xarray.Dataset
        Dimensions ``epoch`` × ``cand`` (the ``n_candidates`` RRHs nearest the train):
        truth (position, speed, acceleration; per candidate 3-D distance, AOD, delay,
        received power) and estimates (detections, AOD, TOA, combined peak).
    """
    epochs = np.asarray(epochs, dtype=np.int64)
    dep, radio = scn.deployment, scn.radio
    t = epochs * scn.trajectory.dt_s
    x, v, a = scn.trajectory.state(t)
    shadow = ShadowingMap(seed, key + (KEY_SHADOWING,), dep, radio)
    pool = qpsk_pool(make_rng(seed, key + (KEY_POOL,)), scn.pool_size)
    syn = Synthesizer(scn.receiver, scn.profile, pool, scn.n_sinusoids, scn.full_channel_range_m,
                      scn.data_beam)
    receivers = [("seed", scn.receiver, scn.detector)] + list(scn.variants)
    for _, rc, _ in receivers:
        if rc.decimation != scn.receiver.decimation or rc.ssb_pattern != scn.receiver.ssb_pattern:
            raise ValueError("receiver variants must share decimation and ssb_pattern")
    cors = [Correlator(rc, det, scn.pfa) for _, rc, det in receivers]
    n_r = len(receivers)
    n_e, n_c = epochs.size, scn.n_candidates
    out = {name: np.full((n_e, n_c), np.nan) for name in ("d3d_m", "aod_true_rad", "rx_power_dbm")}
    est = {name: np.full((n_r, n_e, n_c), np.nan) for name in ("aod_hat_rad", "toa_hat_s", "peak", "best_score")}
    out["rrh"] = np.zeros((n_e, n_c), dtype=np.int64)
    out["panel"] = np.zeros((n_e, n_c), dtype=np.int64)
    est["n_detected"] = np.zeros((n_r, n_e, n_c), dtype=np.int64)
    sinr_proxy = np.full(n_e, np.nan)
    n_id1, n_id2 = dep.n_id()
    corr_keep = {}
    for i, (e, xe, ve) in enumerate(zip(epochs, x, v, strict=True)):
        lb = link_budget(float(xe), float(ve), dep, radio, scn.rrh_array, scn.train_array, shadow, scn.shadowing)
        rng = make_rng(seed, key + (KEY_EPOCH, int(e)))
        z, s_min = syn(lb.links, rng, t0_s=float(t[i]), d2d_m=lb.link_d2d_m)
        cand = dep.nearest(float(xe), n_c)
        # a candidate beyond radio.range_m (sparse RRHs near the track's ends) sends nothing:
        # its truth is the geometry to the reference point, its received power NaN, and a
        # detection of it a false alarm
        inr = np.isin(cand, lb.rrh)
        pos = np.searchsorted(lb.rrh, cand[inr])
        out["rrh"][i] = cand
        out["d3d_m"][i] = dep.distance_3d_m(np.full(n_c, float(xe)), cand)
        out["aod_true_rad"][i] = dep.aod_rad(np.full(n_c, float(xe)), cand)
        out["d3d_m"][i, inr] = lb.d3d_m[pos]
        out["aod_true_rad"][i, inr] = lb.aod_rad[pos]
        out["rx_power_dbm"][i, inr] = lb.rx_power_dbm[pos]
        if lb.panel is not None:
            out["panel"][i, inr] = lb.panel[pos]
        spectra = {}  # window FFTs shared by receivers with the same window length
        for j, cor in enumerate(cors):
            if cor.n_win not in spectra:
                spectra[cor.n_win] = cor.window_spectra(z, s_min)
            res = cor.correlate(z, s_min, n_id1[cand], n_id2[cand],
                                keep_corr=(j == 0 and int(e) in keep_corr_epochs), zf=spectra[cor.n_win])
            est["aod_hat_rad"][j, i] = res.aod_rad
            est["toa_hat_s"][j, i] = res.toa_samples / SAMPLE_RATE_HZ
            est["peak"][j, i] = res.peak_comb
            est["n_detected"][j, i] = res.detected.sum(axis=1)
            score = np.where(res.detected, (res.eta - res.mu) / np.maximum(res.sigma, 1e-30), -np.inf)
            est["best_score"][j, i] = np.where(res.detected.any(axis=1), score.max(axis=1), np.nan)
            if res.corr is not None:
                corr_keep[int(e)] = (res.corr, cand)
        p_all = 10 ** (lb.rx_power_dbm / 10)
        sinr_proxy[i] = 10 * np.log10(p_all.max() / (p_all.sum() - p_all.max()))
    cd = ("epoch", "cand")
    rd = ("receiver", "epoch", "cand")
    ds = xr.Dataset(
        {
            "t": (("epoch",), t, {"units": "s", "long_name": "time of the burst start (truth instant)"}),
            "x_true": (("epoch",), x, {"units": "m", "long_name": "true train position along the track"}),
            "v_true": (("epoch",), v, {"units": "m s-1", "long_name": "true train speed"}),
            "a_true": (("epoch",), a, {"units": "m s-2", "long_name": "true train acceleration"}),
            "rrh": (cd, out["rrh"], {"units": "1", "long_name": "candidate RRH index (nearest first)"}),
            "d3d": (cd, out["d3d_m"], {"units": "m", "long_name": "true 3-D train-RRH distance"}),
            "toa_true": (cd, out["d3d_m"] / SPEED_OF_LIGHT_M_S, {"units": "s", "long_name": "true propagation delay"}),
            "aod_true": (cd, out["aod_true_rad"], {"units": "rad", "long_name": "true azimuth of departure at the RRH"}),
            "rx_power": (cd, out["rx_power_dbm"], {"units": "dBm", "long_name": "received power with the best beam"}),
            "panel": (cd, out["panel"], {"units": "1", "long_name": "train panel receiving the RRH more strongly (0 head, 1 tail); distance, delay and angles are to it"}),
            "train_panel_x": (("panel_id",), np.asarray(scn.train_array.panel_x_m, float),
                              {"units": "m", "long_name": "along-track position of the head (0) and tail (1) panels from the train's reference point"}),
            "aod_hat": (rd, est["aod_hat_rad"], {"units": "rad", "long_name": "AOD estimate (seed eq. 7), NaN if nothing detected"}),
            "toa_hat": (rd, est["toa_hat_s"], {"units": "s", "long_name": "TOA estimate (seed eq. 9), NaN if nothing detected"}),
            "peak": (rd, est["peak"], {"units": "1", "long_name": "combined correlation peak (decimated-rate units)"}),
            "best_score": (rd, est["best_score"], {"units": "1", "long_name": "largest (eta - mu)/sigma over detected blocks"}),
            "n_detected": (rd, est["n_detected"], {"units": "1", "long_name": "SS blocks detected (seed eq. 6)"}),
            "sir_best": (("epoch",), sinr_proxy, {"units": "dB", "long_name": "strongest RRH power over the sum of the others"}),
        },
        coords={
            "epoch": ("epoch", epochs, {"units": "1", "long_name": "measurement epoch index (dt apart)"}),
            "cand": ("cand", np.arange(n_c), {"units": "1", "long_name": "candidate rank by distance"}),
            "receiver": ("receiver", [name for name, _, _ in receivers], {"units": "1", "long_name": "receiver variant"}),
            "panel_id": ("panel_id", [0, 1], {"units": "1", "long_name": "train panel: 0 head, 1 tail"}),
        },
    )
    if corr_keep:
        e0 = sorted(corr_keep)[0]
        corr, cand = corr_keep[e0]
        ds["corr_sample"] = (("cand", "block", "lag"), corr,
                             {"units": "1", "long_name": f"|r_i[k]| of epoch {e0} (decimated lags)"})
        ds["corr_sample_epoch"] = ((), e0, {"units": "1", "long_name": "epoch of corr_sample"})
    return ds


def scenario_from_config(c: dict) -> Scenario:
    """Build the :class:`Scenario` from the ``nr`` section of the workflow config."""
    from railradio.nr.antenna import RrhArray, TrainArray

    rx = c["receiver"]
    # [ours] search window bounded by the geometry: lags covering delays up to range / c
    search_lags = (None if rx.get("search_range_m") is None
                   else int(np.ceil(rx["search_range_m"] / SPEED_OF_LIGHT_M_S * SAMPLE_RATE_HZ)))
    return Scenario(
        trajectory=Trajectory(tuple(tuple(map(float, p)) for p in c["trajectory"]["phases"]),
                              float(c["trajectory"]["dt_s"])),
        deployment=Deployment(**{k: float(v) for k, v in c["deployment"].items()}),
        radio=RadioParams(**{k: float(v) for k, v in c["radio"].items()}),
        rrh_array=RrhArray(n_elements=int(c["antenna"]["rrh_elements"]), n_beams=int(c["antenna"]["n_beams"])),
        train_array=TrainArray(n_elements=int(c["antenna"]["train_elements"]),
                               panel_x_m=tuple(float(v) for v in c["antenna"].get("train_panels_x_m", (0.0, 0.0)))),
        receiver=ReceiverConfig(decimation=int(rx["decimation"]), ssb_pattern=rx["ssb_pattern"],
                                n_blocks=int(c["antenna"]["n_beams"]), toa_blocks=rx["toa_blocks"],
                                subsample=bool(rx["subsample"]), template=rx["template"],
                                search_lags=search_lags),
        tdl=c["channel"]["tdl"], delay_spread_s=float(c["channel"]["delay_spread_s"]),
        detector=rx["detector"], pfa=float(rx["pfa"]), n_candidates=int(rx["n_candidates"]),
        variants=tuple(
            (name, ReceiverConfig(decimation=int(rx["decimation"]), ssb_pattern=rx["ssb_pattern"],
                                  n_blocks=int(c["antenna"]["n_beams"]), toa_blocks=v["toa_blocks"],
                                  subsample=bool(v["subsample"]), template=v["template"],
                                  search_lags=search_lags), v["detector"])
            for name, v in c.get("receiver_variants", {}).items()),
        full_channel_range_m=float(c["channel"]["full_channel_range_m"]),
        n_sinusoids=int(c["channel"]["n_sinusoids"]),
        data_beam=c.get("traffic", {}).get("data_beam", "train"),
    )


def shard_epochs(n_epochs: int, n_shards: int, shard: int) -> np.ndarray:
    """Epoch indices of one shard: contiguous, near-equal blocks."""
    if not 0 <= shard < n_shards:
        raise ValueError(f"shard must be in 0..{n_shards - 1}, got {shard!r}")
    edges = np.linspace(0, n_epochs, n_shards + 1).round().astype(int)
    return np.arange(edges[shard], edges[shard + 1])
