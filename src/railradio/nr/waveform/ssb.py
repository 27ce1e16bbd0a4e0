"""SS-block resource grid and the correlator's reference (TS 38.211 §7.4.3; source §1.3).

An SS block is 4 OFDM symbols × 240 subcarriers at the carrier centre (block subcarrier
0 = carrier subcarrier -120). Symbol 0: PSS on 56..182, zeros elsewhere; symbol 1: PBCH
on 0..239; symbol 2: SSS on 56..182, PBCH on 0..47 and 192..239, zeros on 48..55 and
183..191; symbol 3: PBCH on 0..239. PBCH and the full-buffer data elsewhere are random
QPSK (source: "full buffer traffic on the whole band"); all at equal EPRE.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from railradio.nr.waveform.numerology import N_ACTIVE, N_FFT, Numerology
from railradio.nr.waveform.sequences import pss, sss

SSB_WIDTH = 240
SSB_FIRST_K = -120  # carrier subcarrier of block subcarrier 0
PSS_SSS_FIRST = 56  # block subcarriers 56..182


def carrier_k(block_sc: NDArray) -> NDArray[np.int64]:
    """Carrier subcarrier index (relative to the centre) of SS-block subcarriers.

    Parameters
    ----------
    block_sc : int or numpy.ndarray of int
        Block subcarrier indices (0..239), any shape.

    Returns
    -------
    numpy.ndarray of int64
        Carrier subcarrier k = block_sc - 120, the shape of ``block_sc``.
    """
    return SSB_FIRST_K + np.asarray(block_sc)


def kbin(k: NDArray, n_fft: int) -> NDArray[np.int64]:
    """FFT bin of carrier subcarrier k for an n_fft-point FFT (k must be in [-n/2, n/2)).

    Parameters
    ----------
    k : int or numpy.ndarray of int
        Carrier subcarrier indices, any shape (not checked).
    n_fft : int
        FFT size.

    Returns
    -------
    numpy.ndarray of int64
        k mod n_fft, the shape of ``k``.
    """
    return np.asarray(k) % n_fft


# Per SS-block symbol: (content mask kinds) as carrier-k ranges
def _ranges() -> dict:
    pss_k = carrier_k(np.arange(PSS_SSS_FIRST, PSS_SSS_FIRST + 127))
    block_k = carrier_k(np.arange(SSB_WIDTH))
    sym2_pbch = carrier_k(np.r_[0:48, 192:240])
    sym0_zero = carrier_k(np.r_[0:56, 183:240])
    sym2_zero = carrier_k(np.r_[48:56, 183:192])
    return {"seq": pss_k, "block": block_k, "sym2_pbch": sym2_pbch, "sym0_zero": sym0_zero, "sym2_zero": sym2_zero}


RANGES = _ranges()


def qpsk_pool(rng: np.random.Generator, n_pool: int) -> NDArray[np.complex64]:
    """``n_pool`` random unit-power QPSK vectors over all N_FFT bins, FFT-bin order,
    zero outside the 600 active subcarriers: shape [n_pool, N_FFT].

    Parameters
    ----------
    rng : numpy.random.Generator
        Generator of the bits.
    n_pool : int
        Number of vectors.

    Returns
    -------
    numpy.ndarray of complex64
        [n_pool, N_FFT] symbols of unit power on the active subcarriers, 0 elsewhere.
    """
    bits = rng.integers(0, 2, size=(n_pool, N_FFT, 2))
    sym = ((1 - 2 * bits[..., 0]) + 1j * (1 - 2 * bits[..., 1])) / np.sqrt(2)
    k = np.fft.fftfreq(N_FFT, 1.0 / N_FFT)
    sym[:, (k < -N_ACTIVE // 2) | (k >= N_ACTIVE // 2)] = 0
    return sym.astype(np.complex64)


def band_bins(num: Numerology) -> NDArray[np.int64]:
    """The full-rate FFT bins (N_FFT order) of the subcarriers synthesized at ``num``'s rate,
    in the reduced FFT's bin order.

    Parameters
    ----------
    num : Numerology
        The synthesis rate F_s/D (FFT size N_FFT/D).

    Returns
    -------
    numpy.ndarray of int64
        Full-rate bin of each reduced bin: [num.n_fft].
    """
    k = np.fft.fftfreq(num.n_fft, 1.0 / num.n_fft).astype(np.int64)
    return k % N_FFT


def burst_grid(
    num: Numerology,
    symbols: NDArray[np.int64],
    ssb_first: NDArray[np.int64],
    n_id1: int,
    n_id2: int,
    pool: NDArray[np.complex64],
    pool_idx: NDArray[np.int64],
) -> tuple[NDArray[np.complex64], NDArray[np.int64]]:
    """The transmit grid of one RRH over ``symbols`` at ``num``'s rate.

    Parameters
    ----------
    num : Numerology
        The synthesis rate F_s/D.
    symbols : numpy.ndarray of int64
        Symbol indices (from the burst's first subframe start; negative = before it): [n_symbols].
    ssb_first : numpy.ndarray of int64
        First symbol of each SS block: [n_blocks].
    n_id1 : int
        N_ID^(1) (0..335): selects the SSS.
    n_id2 : int
        N_ID^(2) (0..2): selects the PSS and SSS.
    pool : numpy.ndarray of complex64
        QPSK pool [P, N_FFT] (:func:`qpsk_pool`).
    pool_idx : numpy.ndarray of int64
        One pool index per symbol (data and PBCH): [n_symbols].

    Returns
    -------
    grid : numpy.ndarray of complex64
        [n_symbols, num.n_fft] unit-EPRE subcarrier values, reduced-FFT bin order.
    block_of_symbol : numpy.ndarray of int64
        SS-block index carried by each symbol, -1 for data-only symbols: [n_symbols].
    """
    bins = band_bins(num)
    grid = pool[pool_idx][:, bins].copy()  # [S, n]
    block_of = np.full(symbols.shape, -1, dtype=np.int64)
    pos = {int(s): i for i, s in enumerate(symbols)}
    d_pss = pss(n_id2).astype(np.complex64)
    d_sss = sss(n_id1, n_id2).astype(np.complex64)
    n = num.n_fft
    for b, f in enumerate(ssb_first):
        for off in range(4):
            i = pos.get(int(f) + off)
            if i is None:
                continue
            block_of[i] = b
            row = grid[i]
            if off == 0:
                row[kbin(RANGES["sym0_zero"], n)] = 0
                row[kbin(RANGES["seq"], n)] = d_pss
            elif off == 2:
                row[kbin(RANGES["sym2_zero"], n)] = 0
                row[kbin(RANGES["seq"], n)] = d_sss
            # off 1, 3 and the PBCH parts of symbol 2: pool QPSK already there
    return grid, block_of


def reference_waveform(
    num: Numerology, n_id1: int, n_id2: int, first_symbol: int, template: str = "pss_sss"
) -> NDArray[np.complex64]:
    """The correlator's reference b of one SS block (source eq. 4): PSS in the block's symbol 0
    and SSS in its symbol 2 (with their CPs), every other subcarrier and symbol empty;
    time samples from the CP start of symbol 0 to the end of symbol 2, unit EPRE.
    ``template="sss"`` [ours] keeps only the SSS (unique per cell: the PSS repeats every
    third RRH, whose stronger PSS otherwise leaks into a weaker cell's correlation).

    Parameters
    ----------
    num : Numerology
        The sample rate F_s/D of the waveform.
    n_id1 : int
        Cell-ID group N_ID^(1) (0..335); with ``n_id2`` it selects the SSS.
    n_id2 : int
        N_ID^(2) (0..2): selects the PSS.
    first_symbol : int
        OFDM symbol index of the block's first symbol (sets the CP lengths,
        :meth:`Numerology.cp_length`).
    template : str
        ``"pss_sss"`` or ``"sss"``.

    Returns
    -------
    numpy.ndarray of complex64
        The reference's time samples at F_s/D (three symbols with their CPs).

    Raises
    ------
    ValueError
        When ``template`` is neither ``"pss_sss"`` nor ``"sss"``.
    """
    if template not in ("pss_sss", "sss"):
        raise ValueError(f"template must be 'pss_sss' or 'sss', got {template!r}")
    n = num.n_fft
    out = []
    for off in range(3):
        sym = first_symbol + off
        x = np.zeros(n, dtype=np.complex64)
        if off == 0 and template == "pss_sss":
            x[kbin(RANGES["seq"], n)] = pss(n_id2)
        elif off == 2:
            x[kbin(RANGES["seq"], n)] = sss(n_id1, n_id2)
        y = n * np.fft.ifft(x)
        cp = int(num.cp_length(sym))
        out.append(np.concatenate([y[n - cp :], y]))
    return np.concatenate(out).astype(np.complex64)
