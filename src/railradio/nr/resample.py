"""The receiver's ideal front end between sample rates F_s/D (FFT-domain, over a burst).

:func:`project` is an ideal anti-aliasing filter followed by decimation by D (what a
receiver sampling at F_s/D sees of a full-rate signal); :func:`upsample` is band-limited
interpolation by D, its inverse for a signal inside the decimated band. Both treat the
burst as one period (circular): the burst's first SS-block window starts at least four
symbols (≥ 4 400 full-rate samples) after its first sample, where the wrap-around's
1/(π n) tails are below 1e-4 of the amplitude.
"""

from __future__ import annotations

import numpy as np
import scipy.fft as sfft
from numpy.typing import NDArray


def _check(factor: int) -> None:
    if isinstance(factor, bool) or not isinstance(factor, (int, np.integer)) or factor < 1:
        raise ValueError(f"factor must be an integer >= 1, got {factor!r}")


def project(z: NDArray, factor: int) -> NDArray[np.complex64]:
    """Keep the |f| < F/(2·factor) bins of ``z``'s spectrum and return every ``factor``-th
    sample of the filtered signal (F/factor samples per second; sample m is input sample
    factor·m). The length of ``z`` must be a multiple of ``factor``.

    Parameters
    ----------
    z : numpy.ndarray
        Complex samples at a rate F (one burst, treated as circular).
    factor : int
        Decimation D (integer ≥ 1).

    Returns
    -------
    numpy.ndarray of complex64
        ``len(z) // factor`` samples at F/factor.

    Raises
    ------
    ValueError
        When ``factor`` is not an integer ≥ 1 or ``len(z)`` is not a multiple of it.
    """
    _check(factor)
    n = z.size
    if n % factor:
        raise ValueError(f"the length of z ({n}) must be a multiple of factor ({factor})")
    if factor == 1:
        return np.asarray(z, dtype=np.complex64)
    m = n // factor
    zf = sfft.fft(np.asarray(z, dtype=np.complex64))
    k = sfft.fftfreq(m, 1.0 / m).astype(np.int64) % n  # the m central bins, in m-point order
    return (sfft.ifft(zf[k]) / factor).astype(np.complex64)


def upsample(z: NDArray, factor: int) -> NDArray[np.complex64]:
    """Band-limited interpolation by ``factor`` (zero spectrum outside the input's band):
    ``project(upsample(z, D), D) == z``.

    Parameters
    ----------
    z : numpy.ndarray
        Complex samples at a rate F (one burst, treated as circular).
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
