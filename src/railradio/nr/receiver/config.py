"""The receiver's configuration, shared by the burst synthesizer
(:mod:`railradio.nr.synthesis.synthesizer`) and the correlation receiver (:mod:`railradio.nr.receiver.correlator`):
:class:`ReceiverConfig` (rate, SS-block pattern, lag window, detection settings) and the
row-wise FFT both use (:func:`fft_rows`)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.fft as sfft
from numpy.typing import NDArray

from railradio.nr.waveform.numerology import Numerology, ssb_first_symbols


def fft_rows(a: NDArray[np.complex64], inverse: bool = False, out: NDArray | None = None) -> NDArray[np.complex64]:
    """FFT (or the 1/N-normalized inverse, as ``numpy.fft.ifft``) of each row of ``a``
    [..., N], on one thread, with ``scipy.fft`` (pocketfft, compiled for the wheel's
    baseline instruction set: the result does not depend on the CPU's vector unit).
    ``out``, when given, receives the result (it may be ``a`` itself).

    Parameters
    ----------
    a : numpy.ndarray of complex64
        Rows to transform, [..., N].
    inverse : bool
        Inverse FFT (1/N-normalized) instead of the forward one.
    out : numpy.ndarray or None
        Array receiving the result, [..., N] (``None``: a new array).

    Returns
    -------
    numpy.ndarray of complex64
        The row transforms, [..., N] (``out`` when given).
    """
    f = sfft.ifft if inverse else sfft.fft
    y = f(a, axis=-1, workers=1, overwrite_x=out is a)
    if out is None:
        return y
    if y.ctypes.data != out.ctypes.data:  # overwrite_x already wrote into ``a``'s buffer
        out[...] = y
    return out


@dataclass(frozen=True)
class ReceiverConfig:
    """Receiver and burst settings.

    Parameters
    ----------
    decimation
        D: synthesize and correlate at F_s/D (1, 2, 4 or 8).
    ssb_pattern, n_blocks
        SS-block positions (``source`` or ``caseE``) and blocks per burst (source: 64).
    search_lags
        K, correlation lags per block at the full rate; ``None``: the minimum spacing of
        SS blocks (source eq. 5).
    detect_k_sigma
        Detection threshold η > μ + kσ (source eq. 6: 4).
    n_aod_blocks
        Blocks averaged for the AOD (source eq. 7: 3).
    subsample
        Parabolic sub-sample TOA interpolation [ours; off for the reproduction].

    Raises
    ------
    ValueError
        When ``decimation`` is not 1, 2, 4 or 8, ``ssb_pattern`` is unknown, ``n_blocks`` is
        outside 1..64, ``search_lags`` < 1 or ``detect_k_sigma`` ≤ 0.
    """

    decimation: int = 4
    ssb_pattern: str = "source"
    n_blocks: int = 64
    search_lags: int | None = None
    detect_k_sigma: float = 4.0
    n_aod_blocks: int = 3
    subsample: bool = False
    prescreen_k_sigma: float = 3.0
    template: str = "pss_sss"
    """Correlation reference: PSS + SSS (source) or SSS only [ours]."""
    toa_blocks: int | None = None
    """TOA combining (eq. 8) over all detected blocks (``None``, the source) or over the
    ``toa_blocks`` detected blocks with the largest (η - μ)/σ [ours]."""

    def __post_init__(self) -> None:
        Numerology(self.decimation)
        ssb_first_symbols(self.ssb_pattern, self.n_blocks)
        if self.search_lags is not None and self.search_lags < 1:
            raise ValueError(f"search_lags must be >= 1, got {self.search_lags!r}")
        if not self.detect_k_sigma > 0:
            raise ValueError("detect_k_sigma must be > 0")

    @cached_property
    def num(self) -> Numerology:
        """The :class:`railradio.nr.waveform.numerology.Numerology` of the rate F_s/D."""
        return Numerology(self.decimation)

    @cached_property
    def ssb_first(self) -> NDArray[np.int64]:
        """First OFDM symbol of each SS block (from the burst's first subframe start), int64 [n_blocks]."""
        return ssb_first_symbols(self.ssb_pattern, self.n_blocks)

    @cached_property
    def block_start_full(self) -> NDArray[np.int64]:
        """v_i: first full-rate sample of each block (CP start of its symbol 0), int64 [n_blocks]."""
        return Numerology(1).symbol_start(self.ssb_first)

    @cached_property
    def lags_full(self) -> int:
        """K [full-rate samples]: ``search_lags``, else the minimum spacing of the SS blocks (6576
        for a single block).
        """
        if self.search_lags is not None:
            return int(self.search_lags)
        return int(np.min(np.diff(self.block_start_full))) if self.n_blocks > 1 else 6576

    @cached_property
    def lags(self) -> int:
        """K at the decimated rate: ceil(K/D) [samples at F_s/D]."""
        return -(-self.lags_full // self.decimation)
