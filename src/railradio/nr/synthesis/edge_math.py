"""The edges' mathematics (:mod:`railradio.nr.synthesis.band_edges`): κ(θ), a window's edge
in the DTFT of a windowed tone; Chebyshev points and their Lagrange basis; the tone
segments' interpolation basis; the full-rate sample of a delay and the LOS phasor."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import BarycentricInterpolator

from railradio.nr.waveform.numerology import SAMPLE_RATE_HZ

N_NODES = 6
"""Chebyshev nodes per edge spectrum: the smallest count at which the correction equals the
full-rate burst to float32 rounding on paper-scale epochs (−94 dB of the omitted power with
ρ folded; 6 nodes: −73 dB), ``tests/nr/test_band_edges.py``."""


N_POINTS = (12, 8)
"""Chebyshev points of the tone-domain interpolation (fast path): in the synthesized band and
in each side of the far band. Every kernel the edges take is smooth in the tone index on
each segment (its poles half a band away): measured error with these counts in
``tests/nr/test_band_edges.py``."""


def _chebyshev_lagrange(x: NDArray, r: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The ``r`` Chebyshev points of the first kind on [-1, 1] and the Lagrange basis on them
    evaluated at ``x`` [len(x), r] (scipy's barycentric interpolator of the unit vectors)."""
    nodes = np.cos(np.pi * (2 * np.arange(r) + 1) / (2 * r))
    return nodes, BarycentricInterpolator(nodes, np.eye(r))(np.asarray(x, dtype=np.float64))


def _tone_basis(k_all: NDArray[np.int64], n: int, n_points: tuple[int, int]) -> tuple[NDArray, NDArray]:
    """Lagrange interpolation on Chebyshev points, per tone segment (the band [-n/2, n/2) and
    the far band's two sides): a function f of the tone, smooth on each segment, is
    Σ_j f(κ_j) Ψ[k, j] at every tone k. Returns Ψ [K, R] and the points κ_j [R] (tone units,
    not integers)."""
    segments = [(-n // 2, n // 2, n_points[0])]
    lo_far, hi_far = int(k_all.min()), int(k_all.max()) + 1
    segments += [(lo_far, -n // 2, n_points[1]), (n // 2, hi_far, n_points[1])]
    psi = np.zeros((k_all.size, sum(r for _, _, r in segments)))
    points = []
    col = 0
    for lo, hi, r in segments:
        centre, half = (lo + hi - 1) / 2.0, (hi - 1 - lo) / 2.0
        inside = (k_all >= lo) & (k_all < hi)
        t, lag = _chebyshev_lagrange((k_all[inside] - centre) / half, r)
        psi[np.flatnonzero(inside), col : col + r] = lag
        points.append(centre + half * t)
        col += r
    return psi, np.concatenate(points)


def _ceil_samples(t_s) -> NDArray[np.int64]:
    """The first full-rate sample at or after time(s) ``t_s`` (as the fast path places a delay)."""
    return np.ceil(np.asarray(t_s) * SAMPLE_RATE_HZ - 1e-9).astype(np.int64)


def _los_phasor(p, w_rad_s: float, t_first_s: float, origin0: int, phase0_rad: float) -> NDArray[np.complex128]:
    """The LOS phasor e^{j(w t + φ0)} at full-rate samples ``p`` (sample ``origin0`` received at ``t_first_s``)."""
    return np.exp(1j * (w_rad_s * (t_first_s + (np.asarray(p) - origin0) / SAMPLE_RATE_HZ) + phase0_rad))


def kappa(theta: NDArray) -> NDArray[np.complex128]:
    """κ(θ) = 1/(e^{jθ} - 1): a window's edge in the DTFT of a windowed tone (θ ≠ 0 mod 2π).

    Parameters
    ----------
    theta : numpy.ndarray
        Tone minus analysis frequency [rad/sample].

    Returns
    -------
    numpy.ndarray of complex128
        κ(θ), the shape of ``theta``.
    """
    return 1.0 / (np.exp(1j * np.asarray(theta)) - 1.0)
