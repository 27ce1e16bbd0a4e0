"""TDL-A…E (TR 38.901 Tables 7.7.2-1…5) against an independent transcription, and the
synthesis of the NLOS profiles (no LOS tap) against the brute-force reference."""

import numpy as np
import pytest

from railradio.nr.channel.link import Links
from railradio.nr.channel.tdl import tdl_profile
from railradio.nr.receiver.config import ReceiverConfig
from railradio.nr.receiver.correlator import Correlator
from railradio.nr.synthesis.reference import reference_correlation, reference_received
from railradio.nr.synthesis.synthesizer import Synthesizer
from railradio.nr.waveform.numerology import SAMPLE_RATE_HZ
from railradio.nr.waveform.ssb import qpsk_pool

# Independent transcription of TR 38.901 v17.0.0 Tables 7.7.2-1, -2, -3 and -5, every row
# (normalized delay, power dB), in the tables' order; TDL-E's first row is the specular
# (LOS) part of tap 1. TDL-D (Table 7.7.2-4) is transcribed in full in test_channel.py.
FULL = {
    "TDL-A": [
        (0.0, -13.4),
        (0.3819, 0.0),
        (0.4025, -2.2),
        (0.5868, -4.0),
        (0.4610, -6.0),
        (0.5375, -8.2),
        (0.6708, -9.9),
        (0.5750, -10.5),
        (0.7618, -7.5),
        (1.5375, -15.9),
        (1.8978, -6.6),
        (2.2242, -16.7),
        (2.1718, -12.4),
        (2.4942, -15.2),
        (2.5119, -10.8),
        (3.0582, -11.3),
        (4.0810, -12.7),
        (4.4579, -16.2),
        (4.5695, -18.3),
        (4.7966, -18.9),
        (5.0066, -16.6),
        (5.3043, -19.9),
        (9.6586, -29.7),
    ],
    "TDL-B": [
        (0.0, 0.0),
        (0.1072, -2.2),
        (0.2155, -4.0),
        (0.2095, -3.2),
        (0.2870, -9.8),
        (0.2986, -1.2),
        (0.3752, -3.4),
        (0.5055, -5.2),
        (0.3681, -7.6),
        (0.3697, -3.0),
        (0.5700, -8.9),
        (0.5283, -9.0),
        (1.1021, -4.8),
        (1.2756, -5.7),
        (1.5474, -7.5),
        (1.7842, -1.9),
        (2.0169, -7.6),
        (2.8294, -12.2),
        (3.0219, -9.8),
        (3.6187, -11.4),
        (4.1067, -14.9),
        (4.2790, -9.2),
        (4.7834, -11.3),
    ],
    "TDL-C": [
        (0.0, -4.4),
        (0.2099, -1.2),
        (0.2219, -3.5),
        (0.2329, -5.2),
        (0.2176, -2.5),
        (0.6366, 0.0),
        (0.6448, -2.2),
        (0.6560, -3.9),
        (0.6584, -7.4),
        (0.7935, -7.1),
        (0.8213, -10.7),
        (0.9336, -11.1),
        (1.2285, -5.1),
        (1.3083, -6.8),
        (2.1704, -8.7),
        (2.7105, -13.2),
        (4.2589, -13.9),
        (4.6003, -13.9),
        (5.4902, -15.8),
        (5.6077, -17.1),
        (6.3065, -16.0),
        (6.6374, -15.7),
        (7.0427, -21.6),
        (8.6523, -22.8),
    ],
    "TDL-E": [
        (0.0, -0.03),
        (0.0, -22.03),
        (0.5133, -15.8),
        (0.5440, -18.1),
        (0.5630, -19.8),
        (0.5440, -22.9),
        (0.7112, -22.4),
        (1.9092, -18.6),
        (1.9293, -20.8),
        (1.9589, -22.6),
        (2.6426, -22.3),
        (3.7136, -25.6),
        (5.4524, -20.2),
        (12.0034, -29.8),
        (20.6519, -29.2),
    ],
}
LOS_FIRST = {"TDL-A": False, "TDL-B": False, "TDL-C": False, "TDL-E": True}
# number of Rayleigh taps, first and last row, LOS power [dB] (None: NLOS) and the Rice
# factor K of the first tap [dB] stated in §7.7.2 (TDL-D from Table 7.7.2-4)
TABLES = {
    "TDL-A": dict(n=23, first=(0.0, -13.4), last=(9.6586, -29.7), los_db=None, k_db=None),
    "TDL-B": dict(n=23, first=(0.0, 0.0), last=(4.7834, -11.3), los_db=None, k_db=None),
    "TDL-C": dict(n=24, first=(0.0, -4.4), last=(8.6523, -22.8), los_db=None, k_db=None),
    "TDL-D": dict(n=13, first=(0.0, -13.5), last=(12.525, -27.7), los_db=-0.2, k_db=13.3),
    "TDL-E": dict(n=14, first=(0.0, -22.03), last=(20.6519, -29.2), los_db=-0.03, k_db=22.0),
}
# the strongest tap of each NLOS table (normalized delay, 0 dB)
NLOS_STRONGEST = {"TDL-A": 0.3819, "TDL-B": 0.0, "TDL-C": 0.6366}


@pytest.mark.parametrize("name", sorted(FULL))
def test_every_row_matches_the_independent_transcription(name):
    """Every tap's delay and power of the package table against the transcription above."""
    rows = FULL[name]
    raw = np.array([10 ** (db / 10) for _, db in rows])
    raw /= raw.sum()
    p = tdl_profile(name, 1.0)
    if LOS_FIRST[name]:
        assert p.los_power == pytest.approx(raw[0], rel=1e-12)
        raw, rows = raw[1:], rows[1:]
    else:
        assert p.los_power == 0.0
    np.testing.assert_allclose(p.powers, raw, rtol=1e-12)
    np.testing.assert_allclose(p.delays_s, [d for d, _ in rows], rtol=0, atol=1e-15)


def _raw_total(name: str, p) -> float:
    """Sum of the table's linear powers, from the normalized profile and one known row."""
    t = TABLES[name]
    return 10 ** (t["first"][1] / 10) / p.powers[0]


@pytest.mark.parametrize("name", sorted(TABLES))
def test_profile_matches_independent_transcription(name):
    ds = 30e-9
    t = TABLES[name]
    p = tdl_profile(name, ds)
    assert p.powers.size == t["n"]
    assert p.delays_s[0] == pytest.approx(t["first"][0] * ds, abs=1e-18)
    assert p.delays_s[-1] == pytest.approx(t["last"][0] * ds, rel=1e-12)
    total = _raw_total(name, p)
    assert 10 * np.log10(p.powers[-1] * total) == pytest.approx(t["last"][1], abs=1e-9)
    assert p.los_power + p.powers.sum() == pytest.approx(1.0, rel=1e-12)
    if t["los_db"] is None:
        assert p.los_power == 0.0 and p.rice_k_db == float("-inf")
        k = np.argmax(p.powers)
        assert p.delays_s[k] == pytest.approx(NLOS_STRONGEST[name] * ds, abs=1e-18)
        assert 10 * np.log10(p.powers[k] * total) == pytest.approx(0.0, abs=1e-9)
    else:
        assert 10 * np.log10(p.los_power * total) == pytest.approx(t["los_db"], abs=1e-9)
        assert p.rice_k_db == pytest.approx(t["k_db"], abs=0.01)


@pytest.mark.parametrize("name", sorted(TABLES))
def test_normalized_tables_have_unit_rms_delay_spread(name):
    """TR 38.901 §7.7.2: the delays are normalized to an RMS delay spread of 1 — a check
    of the whole transcription (a wrong delay or power moves it). TDL-D: 0.994 (its LOS
    split as tabulated)."""
    p = tdl_profile(name, 1.0)
    pw = np.r_[p.los_power, p.powers]
    d = np.r_[p.los_delay_s, p.delays_s]
    mean = (pw * d).sum()
    assert np.sqrt((pw * d**2).sum() - mean**2) == pytest.approx(1.0, abs=0.01)


def test_nlos_profile_synthesis_matches_the_reference():
    """TDL-A (no LOS tap), 468 km/h Doppler, noiseless: the fast synthesis/correlation
    against the per-sample full-rate reference on the same draws (the bound of
    tests/nr/test_receiver.py), and the TOA within the profile's delay extent."""
    rng = np.random.default_rng(7)
    cfg = ReceiverConfig(decimation=4, n_blocks=4)
    cfg1 = ReceiverConfig(decimation=1, n_blocks=4)
    pool = qpsk_pool(rng, 16)
    prof = tdl_profile("TDL-A", 20e-9)
    f_d = 130.0 / 0.01
    links = Links(
        n_id1=np.array([5]),
        n_id2=np.array([1]),
        tau_s=np.array([400.3]) / SAMPLE_RATE_HZ,
        amp=np.array([1.0]),
        beam_amp=np.ones((1, 64)),
        data_amp=np.ones(1),
        f_los_hz=np.array([0.99 * f_d]),
        phase0=np.zeros(1),
        doppler_hz=f_d,
        noise_psd_w_hz=0.0,
    )
    syn = Synthesizer(cfg, prof, pool, data_beam="train")
    draws = syn.draws(links, rng)
    z, s_min = syn(links, rng, noise=False, draws=draws)
    assert np.isfinite(z).all() and np.abs(z).max() > 0
    z1 = reference_received(cfg1, links, prof, pool, draws, syn._span["symbols"])
    fast = Correlator(cfg).correlate(z, s_min, np.array([5]), np.array([1]), keep_corr=True)
    ref_r = reference_correlation(cfg1, z1, s_min, 5, 1)
    err = np.abs(4 * fast.corr[0] - ref_r[:, np.arange(cfg.lags) * 4]).max() / ref_r.max()
    assert err < 0.10, err
    extent = prof.delays_s.max() * SAMPLE_RATE_HZ
    assert -1.0 <= fast.toa_samples[0] - 400.3 <= extent + 1.0
