"""CP-OFDM numerology of the nr study (source 000 §1.3; TS 38.211 §5.3, µ = 4).

Δf = 240 kHz, N_FFT = 1024, F_s = 245.76 MHz, 600 active subcarriers (50 PRB); a 1 ms
subframe holds 16 slots × 14 symbols; symbols 0 and 112 of a subframe (every 0.5 ms) have
a 200-sample cyclic prefix, the others 72 (16·14·1096 + 2·128 = 245 760 samples).

The receiver may run at a decimated rate F_s/D (``decimation`` D ∈ {1, 2, 4, 8}): the
synchronization signals occupy the central 127 subcarriers, so only the band of the
N_FFT/D central subcarriers is synthesized (CP lengths scale by 1/D; exact for every
subcarrier inside that band).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

SUBCARRIER_SPACING_HZ = 240e3
N_FFT = 1024
SAMPLE_RATE_HZ = SUBCARRIER_SPACING_HZ * N_FFT  # 245.76 MHz
N_ACTIVE = 600
SYMBOLS_PER_SLOT = 14
SLOTS_PER_SUBFRAME = 16
SYMBOLS_PER_SUBFRAME = SYMBOLS_PER_SLOT * SLOTS_PER_SUBFRAME  # 224
CP_NORMAL = 72
CP_LONG = 200  # symbols 0 and 112 of each subframe (l mod 112 == 0)
SAMPLES_PER_SUBFRAME = 245_760


@dataclass(frozen=True)
class Numerology:
    """Sample timing at the full or a decimated rate.

    Parameters
    ----------
    decimation : int
        D: the rate is F_s/D, the FFT size N_FFT/D (1, 2, 4 or 8).

    Raises
    ------
    ValueError
        When ``decimation`` is not 1, 2, 4 or 8.
    """

    decimation: int = 1

    def __post_init__(self) -> None:
        if self.decimation not in (1, 2, 4, 8):
            raise ValueError(f"decimation must be 1, 2, 4 or 8, got {self.decimation!r}")

    @property
    def n_fft(self) -> int:
        """FFT size at this rate, N_FFT / D.

        Returns
        -------
        int
            Useful samples per OFDM symbol.
        """
        return N_FFT // self.decimation

    @property
    def sample_rate_hz(self) -> float:
        """Sample rate F_s / D.

        Returns
        -------
        float
            Sample rate [Hz].
        """
        return SAMPLE_RATE_HZ / self.decimation

    @property
    def subcarriers(self) -> NDArray[np.int64]:
        """Subcarrier index k (relative to the carrier centre) of every FFT bin at this rate,
        in FFT-bin order (0, 1, ..., n/2-1, -n/2, ..., -1); active or not (no mask applied).

        Returns
        -------
        numpy.ndarray of int64
            k of every FFT bin: [n_fft].
        """
        k = np.fft.fftfreq(self.n_fft, 1.0 / self.n_fft).astype(np.int64)
        return k

    def cp_length(self, symbol: NDArray[np.int64] | int) -> NDArray[np.int64]:
        """CP length [samples] of symbol index l (counted from a subframe start).

        Parameters
        ----------
        symbol : int or numpy.ndarray of int
            Symbol indices l, any shape.

        Returns
        -------
        numpy.ndarray of int64
            (200 if l mod 112 == 0 else 72) // D [samples], the shape of ``symbol``.
        """
        sym = np.asarray(symbol)
        long = (sym % (SYMBOLS_PER_SUBFRAME // 2)) == 0
        return np.where(long, CP_LONG, CP_NORMAL) // self.decimation

    def symbol_start(self, symbol: NDArray[np.int64] | int) -> NDArray[np.int64]:
        """First sample (CP start) of symbol l, counted from the first subframe's start.

        Parameters
        ----------
        symbol : int or numpy.ndarray of int
            Symbol indices l (negative: before the first subframe), any shape.

        Returns
        -------
        numpy.ndarray of int64
            Sample index at F_s/D [samples], the shape of ``symbol``.
        """
        sym = np.asarray(symbol, dtype=np.int64)
        sf, l_in = np.divmod(sym, SYMBOLS_PER_SUBFRAME)
        base = (self.n_fft + CP_NORMAL // self.decimation) * l_in
        # the long CPs of symbols 0 and 112 delay every later symbol of the subframe
        extra = np.where(
            l_in == 0, 0, (CP_LONG - CP_NORMAL) // self.decimation * (1 + (l_in > SYMBOLS_PER_SUBFRAME // 2))
        )
        return sf * (SAMPLES_PER_SUBFRAME // self.decimation) + base + extra

    def symbol_length(self, symbol: NDArray[np.int64] | int) -> NDArray[np.int64]:
        """CP + useful length [samples] of symbol l.

        Parameters
        ----------
        symbol : int or numpy.ndarray of int
            Symbol indices l, any shape.

        Returns
        -------
        numpy.ndarray of int64
            cp_length + n_fft [samples], the shape of ``symbol``.
        """
        return self.cp_length(symbol) + self.n_fft


def period_length(m: int) -> int:
    """The front end's period [samples at its output rate] for a burst of ``m`` samples there:
    the smallest integer ≥ ``m`` whose prime factors are 2, 3 and 5, the radices pocketfft
    transforms fastest (:func:`railradio.nr.receiver.frontend.project`).

    Parameters
    ----------
    m : int
        The burst's length at the front end's output rate (≥ 1).

    Returns
    -------
    int
        The period, ≥ ``m`` (``m`` itself when it has no other prime factor).

    Raises
    ------
    ValueError
        When ``m`` is not an integer ≥ 1.
    """
    if isinstance(m, bool) or not isinstance(m, (int, np.integer)) or m < 1:
        raise ValueError(f"m must be an integer >= 1, got {m!r}")
    best = None
    p2 = 1
    while p2 < 2 * m:
        p3 = p2
        while p3 < 2 * m:
            p5 = p3
            while p5 < m:
                p5 *= 5
            best = p5 if best is None else min(best, p5)
            p3 *= 3
        p2 *= 2
    return int(best)


def ssb_first_symbols(pattern: str = "source", n_blocks: int = 64) -> NDArray[np.int64]:
    """First OFDM symbol (from the burst's first subframe start) of each SS block.

    ``"source"``: two blocks per slot from the first slot at symbols {2, 8} + 14 n [ours,
    following the source's "two per slot"]; ``"caseE"``: TS 38.213 §4.1 case E,
    {8, 12, 16, 20, 32, 36, 40, 44} + 56 n, n ∈ {0, 1, 2, 3, 5, 6, 7, 8}.

    Parameters
    ----------
    pattern : str
        ``"source"`` or ``"caseE"``.
    n_blocks : int
        Number of SS blocks, 1..64 (the first ones of the pattern).

    Returns
    -------
    numpy.ndarray of int64
        First symbol index of each block, ascending: [n_blocks].

    Raises
    ------
    ValueError
        When ``pattern`` is unknown or ``n_blocks`` is not in 1..64.
    """
    if pattern == "source":
        first = (np.array([2, 8])[None, :] + 14 * np.arange(32)[:, None]).ravel()
    elif pattern == "caseE":
        n = np.array([0, 1, 2, 3, 5, 6, 7, 8])
        first = (np.array([8, 12, 16, 20, 32, 36, 40, 44])[None, :] + 56 * n[:, None]).ravel()
    else:
        raise ValueError(f"ssb pattern must be 'source' or 'caseE', got {pattern!r}")
    if not 1 <= n_blocks <= 64:
        raise ValueError(f"n_blocks must be in 1..64, got {n_blocks!r}")
    return np.sort(first)[:n_blocks].astype(np.int64)
