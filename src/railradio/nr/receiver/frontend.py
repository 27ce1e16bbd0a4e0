"""The receiver's ideal front end between sample rates F_s/D (FFT-domain, over a burst).

:func:`project` is an ideal anti-aliasing filter followed by decimation by D (what a
receiver sampling at F_s/D sees of a full-rate signal); :func:`upsample` is band-limited
interpolation by D, its inverse for a signal inside the decimated band. Both treat the
burst as one period (circular): the burst's first SS-block window starts at least four
symbols (≥ 4 400 full-rate samples) after its first sample, where the wrap-around's
1/(π n) tails are below 1e-4 of the amplitude.

The period is the burst zero-padded to
:func:`railradio.nr.waveform.numerology.period_length` samples at the output rate: the
smallest length at or above the burst's whose prime factors are 2, 3 and 5, the radices
pocketfft transforms fastest. A paper-scale burst has 62 689 = 11·41·139 samples at F_s/8,
which pocketfft transforms ≈ 3× slower than the 64 000 it is padded to. The padding lies
after the burst's last sample, where the receiver has sampled nothing (no noise). The period
is a boundary condition of the ideal filter, not physics: its far tails (≈ 1/M each, M the
period) gather the noise of the whole burst, so another period moves the filtered noise in
the windows by ≈ 0.5 % RMS (−45 dB; measured on a paper-scale burst against the unpadded
62 689), a noise realization as valid as the other (docs/model/nr.md §4).
"""

from __future__ import annotations

import numpy as np
import scipy.fft as sfft
from numpy.typing import NDArray

from railradio.nr.waveform.numerology import period_length


def _check(factor: int) -> None:
    if isinstance(factor, bool) or not isinstance(factor, (int, np.integer)) or factor < 1:
        raise ValueError(f"factor must be an integer >= 1, got {factor!r}")


def project(z: NDArray, factor: int) -> NDArray[np.complex64]:
    """Keep the |f| < F/(2·factor) bins of ``z``'s spectrum (``z`` zero-padded to the period
    :func:`period_length` of ``len(z) // factor`` output samples) and return every
    ``factor``-th sample of the filtered signal (F/factor samples per second; sample m is
    input sample factor·m). The length of ``z`` must be a multiple of ``factor``.

    Parameters
    ----------
    z : numpy.ndarray
        Complex samples at a rate F (one burst; zero-padded to the period, which the filter
        treats as circular).
    factor : int
        Decimation D (integer ≥ 1).

    Returns
    -------
    numpy.ndarray of complex64
        ``period_length(len(z) // factor)`` samples at F/factor.

    Raises
    ------
    ValueError
        When ``factor`` is not an integer ≥ 1 or ``len(z)`` is not a multiple of it.
    """
    _check(factor)
    n = z.size
    if n % factor:
        raise ValueError(f"the length of z ({n}) must be a multiple of factor ({factor})")
    m = period_length(n // factor)
    if factor == 1:
        return np.pad(np.asarray(z, dtype=np.complex64), (0, m - n))
    zf = sfft.fft(np.asarray(z, dtype=np.complex64), n=m * factor)
    k = sfft.fftfreq(m, 1.0 / m).astype(np.int64) % (m * factor)  # the m central bins, in m-point order
    return (sfft.ifft(zf[k]) / factor).astype(np.complex64)


def upsample(z: NDArray, factor: int) -> NDArray[np.complex64]:
    """Band-limited interpolation by ``factor`` (zero spectrum outside the input's band):
    ``project(upsample(z, D), D) == z`` when ``len(z)`` has no prime factor but 2, 3 and 5
    (otherwise ``project`` pads to a longer period).

    Parameters
    ----------
    z : numpy.ndarray
        Complex samples at a rate F (one period, circular).
    factor : int
        Interpolation factor D (integer ≥ 1).

    Returns
    -------
    numpy.ndarray of complex64
        ``len(z) * factor`` samples at F·factor.

    Raises
    ------
    ValueError
        When ``factor`` is not an integer ≥ 1.
    """
    _check(factor)
    if factor == 1:
        return np.asarray(z, dtype=np.complex64)
    m = z.size
    n = m * factor
    zf = sfft.fft(np.asarray(z, dtype=np.complex64))
    out = np.zeros(n, dtype=np.complex64)
    k = sfft.fftfreq(m, 1.0 / m).astype(np.int64) % n
    out[k] = zf  # the m-point spectrum's bins at their frequencies (its F/2 bin at -F/2, as project keeps it)
    return (sfft.ifft(out) * factor).astype(np.complex64)


def front_end(
    z: NDArray[np.complex64], down: int, up: int, edges: NDArray[np.complex64] | None = None
) -> NDArray[np.complex64]:
    """The synthesized burst ``z`` (rate F) through the front end's ideal filter to F/``down``,
    the edges' spectrum ``edges`` added there, and band-limited-interpolated by ``up``:
    ``upsample(project(z, down) + IFFT(edges), up)`` in one spectral pass (over the period
    m = :func:`period_length` of n/down samples).

    Parameters
    ----------
    z : numpy.ndarray of complex64
        The burst at the synthesis rate F, [n] (n a multiple of ``down``; zero-padded to the
        period m·down).
    down, up : int
        The front end's decimation from F and the interpolation to the lag grid (integers ≥ 1).
    edges : numpy.ndarray of complex64 or None
        The band's edges as a spectrum on the front end's m bins, m-point order
        (:class:`SpectralBandEdges`).

    Returns
    -------
    numpy.ndarray of complex64
        [m·up] samples at F·up/down.

    Raises
    ------
    ValueError
        When ``down`` or ``up`` is not an integer ≥ 1, ``len(z)`` is not a multiple of
        ``down``, or ``edges`` has not m bins.
    """
    for name, v in (("down", down), ("up", up)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
            raise ValueError(f"{name} must be an integer >= 1, got {v!r}")
    n = z.size
    if n % down:
        raise ValueError(f"the length of z ({n}) must be a multiple of down ({down})")
    m = period_length(n // down)
    if edges is not None and edges.shape != (m,):
        raise ValueError(f"edges must have {m} bins, got shape {edges.shape}")
    k = sfft.fftfreq(m, 1.0 / m).astype(np.int64)  # the m central bins, m-point order
    zf = sfft.fft(np.asarray(z, dtype=np.complex64), n=m * down, workers=1)
    spec = zf[k % (m * down)] * np.float32(1.0 / down)
    if edges is not None:
        spec += edges
    out = np.zeros(m * up, dtype=np.complex64)
    out[k % (m * up)] = spec
    return (sfft.ifft(out, workers=1, overwrite_x=True) * np.float32(up)).astype(np.complex64, copy=False)
