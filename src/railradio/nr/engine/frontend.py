"""The receiver's front end in one spectral pass: the band synthesis' spectrum cut to the
front end's band (:func:`railradio.nr.receiver.frontend.project`), the band's edges added there
(:class:`railradio.nr.synthesis.band_edges.BandEdges`, whose sum is already a spectrum before its last
IFFT) and the result interpolated to the correlation's lag grid
(:func:`railradio.nr.receiver.frontend.upsample`) — two FFTs instead of the five of project, the
edges' return to time and upsample. The period of the ideal filter is project's (the burst
zero-padded to :func:`railradio.nr.waveform.numerology.period_length`): the result equals the
three steps to float32 rounding.
"""

from __future__ import annotations

import numpy as np

from railradio.nr.engine.simulate import KEY_EPOCH, KEY_POOL, Burst, Scenario, Synthesis
from railradio.nr.receiver.frontend import front_end
from railradio.nr.synthesis.band_edges import SpectralBandEdges
from railradio.nr.waveform.ssb import qpsk_pool
from railradio.rng import make_rng


class SpectralSynthesis(Synthesis):
    """:class:`railradio.nr.engine.simulate.Synthesis` whose bursts come out on the correlation's lag
    grid F_s/D_c through :func:`front_end` (the same draws, channel and burst).

    Parameters
    ----------
    scn : Scenario
        The scenario.
    seed : int
        The config seed.
    key : tuple of int
        The realization's spawn key.
    """

    def __init__(self, scn: Scenario, seed: int, key: tuple[int, ...]):
        super().__init__(scn, seed, key)
        d_fe = scn.receiver.decimation
        d_c = d_fe if scn.search_decimation is None else int(scn.search_decimation)
        self.up = d_fe // d_c
        if self.edges is not None:
            pool = qpsk_pool(make_rng(seed, key + (KEY_POOL,)), scn.pool_size)
            self.edges = SpectralBandEdges(self.syn, pool, d_fe)

    def __call__(self, epoch: int) -> Burst:
        """The received burst of ``epoch`` on the lag grid (``Burst.z`` at F_s/D_c) and its truth."""
        x, v, a, lb, serving = self.advance(epoch)
        t = epoch * self.scn.trajectory.dt_s
        link_rrh = lb.rrh if lb.link_rrh is None else lb.link_rrh
        rng = make_rng(self.seed, self.key + (KEY_EPOCH, int(epoch)))
        draws = self.syn.draws(lb.links, rng)
        serv = np.asarray(link_rrh) == serving
        z, s_min = self.syn(lb.links, rng, t0_s=t, d2d_m=lb.link_d2d_m, serving=serv, draws=draws)
        edges = None
        if self.edges is not None:
            edges = self.edges(lb.links, draws, t, lb.link_d2d_m, serv, gains=self.syn.kept_gains)
        return Burst(front_end(z, self.down, self.up, edges), s_min, x, v, a, lb, serving)
