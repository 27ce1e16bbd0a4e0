"""The receiver's front end in one spectral pass: the band synthesis' spectrum cut to the
front end's band (:func:`railradio.nr.resample.project`), the band's edges added there
(:class:`railradio.nr.band_edges.BandEdges`, whose sum is already a spectrum before its last
IFFT) and the result interpolated to the correlation's lag grid
(:func:`railradio.nr.resample.upsample`) — two FFTs instead of the five of project, the
edges' return to time and upsample. The burst is still one period of the ideal filter, of the
same length: the result equals the three steps to float32 rounding.
"""

from __future__ import annotations

import numpy as np
import scipy.fft as sfft
from numpy.typing import NDArray

from railradio.nr.band_edges import BandEdges, _chebyshev_lagrange
from railradio.nr.engine import kernels
from railradio.nr.simulate import KEY_EPOCH, KEY_POOL, Burst, Scenario, Synthesis
from railradio.nr.ssb import qpsk_pool
from railradio.rng import make_rng


class SpectralBandEdges(BandEdges):
    """:class:`BandEdges` returning the edges' DFT on the front end's m bins (m-point order,
    the spectrum of what :class:`BandEdges` returns in time) instead of their samples; each
    link's values added around the symbol starts by a compiled loop
    (:func:`railradio.nr.engine.kernels.scatter_rows`)."""

    def _scatter(self, acc, base, lo: int, local) -> None:
        kernels.scatter_rows(acc, np.asarray(base, dtype=np.int64), int(lo), np.ascontiguousarray(local))

    def _spectrum(self, acc, m_full) -> NDArray[np.complex64]:
        m = m_full // self.d_fe
        per_node = sfft.fft(np.ascontiguousarray(acc.T).astype(np.complex64), axis=1, workers=1)
        if self._weights is None or self._weights.shape[1] != m:  # ν_q / (π/D_fe) at each bin
            lag = _chebyshev_lagrange(sfft.fftfreq(m, 1.0 / m) / (m / 2.0), self.x_nodes.size)[1]
            self._weights = np.ascontiguousarray(lag.T).astype(np.complex64)
        per_node *= self._weights
        return (per_node.sum(axis=0) / self.d_fe).astype(np.complex64)


def front_end(
    z: NDArray[np.complex64], down: int, up: int, edges: NDArray[np.complex64] | None = None
) -> NDArray[np.complex64]:
    """The synthesized burst ``z`` (rate F) through the front end's ideal filter to F/``down``,
    the edges' spectrum ``edges`` added there, and band-limited-interpolated by ``up``:
    ``upsample(project(z, down) + IFFT(edges), up)`` in one spectral pass.

    Parameters
    ----------
    z : numpy.ndarray of complex64
        The burst at the synthesis rate F, [n] (n a multiple of ``down``; one period).
    down, up : int
        The front end's decimation from F and the interpolation to the lag grid (integers ≥ 1).
    edges : numpy.ndarray of complex64 or None
        The band's edges as a spectrum on the front end's n/down bins, m-point order
        (:class:`SpectralBandEdges`).

    Returns
    -------
    numpy.ndarray of complex64
        [n·up/down] samples at F·up/down.

    Raises
    ------
    ValueError
        When ``down`` or ``up`` is not an integer ≥ 1, ``len(z)`` is not a multiple of
        ``down``, or ``edges`` has not n/down bins.
    """
    for name, v in (("down", down), ("up", up)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
            raise ValueError(f"{name} must be an integer >= 1, got {v!r}")
    n = z.size
    if n % down:
        raise ValueError(f"the length of z ({n}) must be a multiple of down ({down})")
    m = n // down
    if edges is not None and edges.shape != (m,):
        raise ValueError(f"edges must have {m} bins, got shape {edges.shape}")
    k = sfft.fftfreq(m, 1.0 / m).astype(np.int64)  # the m central bins, m-point order
    zf = sfft.fft(np.asarray(z, dtype=np.complex64), workers=1)
    spec = zf[k % n] * np.float32(1.0 / down)
    if edges is not None:
        spec += edges
    out = np.zeros(m * up, dtype=np.complex64)
    out[k % (m * up)] = spec
    return (sfft.ifft(out, workers=1, overwrite_x=True) * np.float32(up)).astype(np.complex64, copy=False)


class SpectralSynthesis(Synthesis):
    """:class:`railradio.nr.simulate.Synthesis` whose bursts come out on the correlation's lag
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
