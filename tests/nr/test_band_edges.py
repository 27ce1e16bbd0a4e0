"""The full band's symbol edges (railradio.nr.band_edges) against the full-rate burst."""

import numpy as np
import pytest

from railradio.nr.band_edges import BandEdges, kappa
from railradio.nr.channel import tdl_profile
from railradio.nr.numerology import SAMPLE_RATE_HZ
from railradio.nr.receiver import ReceiverConfig
from railradio.nr.resample import project
from railradio.nr.ssb import qpsk_pool
from railradio.nr.synthesis import Links, Synthesizer


def _links(n: int, rng) -> Links:
    return Links(
        n_id1=np.arange(n) + 3,
        n_id2=np.arange(n) % 3,
        tau_s=(1000.0 + 1733.3 * np.arange(n) + rng.random(n)) / SAMPLE_RATE_HZ,
        amp=10.0 ** (-np.arange(n) / 2.0),
        beam_amp=rng.random((n, 8)) + 0.2,
        data_amp=np.ones(n),
        f_los_hz=np.linspace(-9e3, 9e3, n),
        phase0=rng.random(n) * 6,
        doppler_hz=1.4e4,
        noise_psd_w_hz=0.0,
    )


@pytest.mark.parametrize(
    "exact_spill, data_beam, far_m",
    [(True, "train", np.inf), (False, "train", np.inf), (True, "serving", 900.0), (True, "none", np.inf)],
)
def test_the_band_synthesis_plus_its_edges_is_the_full_rate_burst(exact_spill, data_beam, far_m):
    """Four links at F_s/4 with TDL-D's thirteen taps at the paper's 20 ns, fractional
    delays, LOS Dopplers and fading at 14 kHz: the front end's view of the band synthesis
    plus the edges equals the full-rate synthesis' (every subcarrier) to float32 rounding
    (1e-6 of the omitted power; measured 1e-9), with the taps' spill exact or wrapped, a
    link beyond ``far_m`` as one non-fading tap, and the SS blocks alone. The edges are no
    detail: the omitted power is more than 1e-4 of the burst's (measured 27–33 dB below it
    on the paper's epochs, above the receiver noise)."""
    rng = np.random.default_rng(5)
    pool = qpsk_pool(rng, 16)
    prof = tdl_profile("TDL-D", 20e-9)
    links = _links(4, rng)
    d2d = np.array([100.0, 500.0, 1000.0, 2000.0])
    kw = dict(full_channel_range_m=far_m, data_beam=data_beam, load=0.7, exact_spill=exact_spill)
    band = Synthesizer(ReceiverConfig(decimation=4, n_blocks=8), prof, pool, **kw)
    full = Synthesizer(ReceiverConfig(decimation=1, n_blocks=8), prof, pool, **kw)
    draws = band.draws(links, np.random.default_rng(9))
    serving = np.array([True, False, False, False])
    common = dict(t0_s=0.37, d2d_m=d2d, draws=draws, serving=serving)
    z_band = project(band(links, None, noise=False, **common)[0], 2)
    z_full = project(full(links, None, noise=False, **common)[0], 8)
    edges = BandEdges(band, pool, 8)(links, draws, 0.37, d2d, serving)
    omitted = np.mean(np.abs(z_full - z_band) ** 2)
    assert omitted > 1e-4 * np.mean(np.abs(z_full) ** 2)
    assert np.mean(np.abs(z_full - z_band - edges) ** 2) < 1e-6 * omitted


def test_kappa_is_the_windowed_tones_edge():
    """A tone over samples s..e-1 sums to (e^{jθe} - e^{jθs}) κ(θ)."""
    theta, s, e = 0.9, 7, 40
    direct = np.sum(np.exp(1j * theta * np.arange(s, e)))
    assert np.isclose(direct, (np.exp(1j * theta * e) - np.exp(1j * theta * s)) * kappa(theta))


def test_bad_decimations_are_refused():
    pool = qpsk_pool(np.random.default_rng(1), 4)
    prof = tdl_profile("TDL-D", 20e-9)
    band = Synthesizer(ReceiverConfig(decimation=4, n_blocks=8), prof, pool)
    with pytest.raises(ValueError, match="d_fe"):
        BandEdges(band, pool, 6)
    with pytest.raises(ValueError, match="d_fe"):
        BandEdges(Synthesizer(ReceiverConfig(decimation=1, n_blocks=8), prof, pool), pool, 8)
    with pytest.raises(ValueError, match="n_nodes"):
        BandEdges(band, pool, 8, n_nodes=1)
