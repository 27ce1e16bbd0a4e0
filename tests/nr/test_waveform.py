"""Numerology, PSS/SSS (against hand transcriptions and m-sequence theory), SS-block grid,
OFDM round trip."""

import numpy as np
import pytest

from railradio.nr import pss, sss
from railradio.nr.waveform.numerology import Numerology, ssb_first_symbols
from railradio.nr.waveform.ssb import RANGES, burst_grid, kbin, qpsk_pool, reference_waveform

# x(0..14) of the PSS m-sequence, worked by hand from x(i+7) = x(i+4) + x(i) mod 2 with
# [x(0)..x(6)] = [0 1 1 0 1 1 1] (TS 38.211 prints it reversed: [x(6)..x(0)] = [1 1 1 0 1 1 0])
PSS_X_HAND = [0, 1, 1, 0, 1, 1, 1, 1, 0, 0, 1, 1, 1, 0, 0]
# SSS: x0(i+7) = x0(i+4) + x0(i), x1(i+7) = x1(i+1) + x1(i), both from [1 0 0 0 0 0 0]
SSS_X0_HAND = [1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 1]
SSS_X1_HAND = [1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 1, 1]


def test_samples_per_subframe_and_cp_lengths():
    num = Numerology()
    assert num.symbol_start(224) - num.symbol_start(0) == 245_760
    assert 16 * 14 * 1096 + 2 * 128 == 245_760
    np.testing.assert_array_equal(
        num.cp_length(np.array([0, 1, 111, 112, 113, 223, 224])), [200, 72, 72, 200, 72, 72, 200]
    )
    assert num.symbol_start(112) == 122_880  # every 0.5 ms
    d4 = Numerology(4)
    assert d4.n_fft == 256 and d4.cp_length(0) == 50 and d4.cp_length(1) == 18
    assert d4.symbol_start(224) == 61_440
    with pytest.raises(ValueError, match="decimation"):
        Numerology(3)


def test_ss_block_positions():
    source = ssb_first_symbols("source")
    assert source.size == 64 and source[:4].tolist() == [2, 8, 16, 22] and source[-1] == 14 * 31 + 8
    case_e = ssb_first_symbols("caseE")
    assert case_e[:8].tolist() == [8, 12, 16, 20, 32, 36, 40, 44]
    assert case_e[8] == 56 + 8 and 4 * 56 + 8 not in case_e  # n = 4 is skipped
    with pytest.raises(ValueError):
        ssb_first_symbols("caseZ")


def test_pss_against_hand_transcription_and_m_sequence_theory():
    d0 = pss(0)
    np.testing.assert_array_equal(d0[:15], 1 - 2 * np.array(PSS_X_HAND))
    # N_ID2 = 1, 2 are cyclic shifts by 43 and 86
    np.testing.assert_array_equal(pss(1), np.roll(d0, -43))
    np.testing.assert_array_equal(pss(2), np.roll(d0, -86))
    # m-sequence: 64 ones / 63 zeros, two-valued periodic autocorrelation (127, -1)
    assert (d0 == -1).sum() == 64
    ac = np.array([np.dot(d0, np.roll(d0, s)) for s in range(127)])
    assert ac[0] == 127 and np.all(ac[1:] == -1)
    with pytest.raises(ValueError, match="n_id2"):
        pss(3)


def test_sss_against_hand_transcription():
    # N_ID1 = N_ID2 = 0: m0 = m1 = 0, d = (1 - 2 x0(n))(1 - 2 x1(n))
    d = sss(0, 0)
    expected = (1 - 2 * np.array(SSS_X0_HAND)) * (1 - 2 * np.array(SSS_X1_HAND))
    np.testing.assert_array_equal(d[:15], expected)
    # m1 = N_ID1 mod 112 shifts x1 only; m0 = 15 floor(N_ID1/112) + 5 N_ID2 shifts x0 only
    x1 = sss(0, 0) * sss(112, 0)  # differ only in m0 = 15: product is x0 vs shifted x0
    assert set(np.unique(x1)) <= {-1, 1}
    seqs = {tuple(sss(n1, n2)) for n1 in range(336) for n2 in range(3)}
    assert len(seqs) == 1008  # all SSS distinct
    with pytest.raises(ValueError, match="n_id1"):
        sss(336, 0)


def test_grid_layout_and_reference():
    num = Numerology(4)
    rng = np.random.default_rng(0)
    pool = qpsk_pool(rng, 8)
    first = ssb_first_symbols("source")
    symbols = np.arange(0, 12)
    grid, block_of = burst_grid(num, symbols, first, 17, 2, pool, rng.integers(0, 8, symbols.size))
    assert block_of.tolist() == [-1, -1, 0, 0, 0, 0, -1, -1, 1, 1, 1, 1]
    n = num.n_fft
    np.testing.assert_array_equal(grid[2, kbin(RANGES["seq"], n)], pss(2))
    np.testing.assert_array_equal(grid[4, kbin(RANGES["seq"], n)], sss(17, 2))
    assert np.all(grid[2, kbin(RANGES["sym0_zero"], n)] == 0)
    assert np.all(grid[4, kbin(RANGES["sym2_zero"], n)] == 0)
    assert np.all(np.abs(grid[0]) == pytest.approx(1.0))  # data on every subcarrier of the band
    b = reference_waveform(num, 17, 2, 2)
    assert b.size == 3 * (256 + 18)
    assert np.allclose(b[274 : 2 * 274], 0)  # symbol 1 empty in the reference
    # equal EPRE: the PSS symbol carries 127 unit subcarriers
    assert np.sum(np.abs(b[18:274]) ** 2) == pytest.approx(127 * 256, rel=1e-5)


def test_ofdm_round_trip():
    num = Numerology(1)
    rng = np.random.default_rng(1)
    x = qpsk_pool(rng, 1)[0]
    y = num.n_fft * np.fft.ifft(x)
    cp = int(num.cp_length(5))
    tx = np.concatenate([y[-cp:], y])
    back = np.fft.fft(tx[cp:]) / num.n_fft
    np.testing.assert_allclose(back, x, atol=1e-5)
    assert np.mean(np.abs(y) ** 2) == pytest.approx(600, rel=1e-4)  # 600 unit-EPRE subcarriers
