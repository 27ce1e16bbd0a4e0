"""The transmitted signal of the nr study: NR numerology (TS 38.211 §5.3), PSS/SSS sequences
(§7.4.2), the SS burst's resource grid and the correlator's reference (§7.4.3), and which RRH
serves the train.
"""

from railradio.nr.waveform.numerology import (
    CP_LONG,
    CP_NORMAL,
    N_ACTIVE,
    N_FFT,
    SAMPLE_RATE_HZ,
    SAMPLES_PER_SUBFRAME,
    SLOTS_PER_SUBFRAME,
    SUBCARRIER_SPACING_HZ,
    SYMBOLS_PER_SLOT,
    SYMBOLS_PER_SUBFRAME,
    Numerology,
    ssb_first_symbols,
)
from railradio.nr.waveform.sequences import N_ID1_MAX, N_ID2_MAX, SEQ_LEN, pci, pss, sss
from railradio.nr.waveform.ssb import (
    PSS_SSS_FIRST,
    RANGES,
    SSB_FIRST_K,
    SSB_WIDTH,
    band_bins,
    burst_grid,
    carrier_k,
    kbin,
    qpsk_pool,
    reference_waveform,
)
from railradio.nr.waveform.traffic import ServingCell, ServingRule

__all__ = [
    "CP_LONG",
    "CP_NORMAL",
    "N_ACTIVE",
    "N_FFT",
    "N_ID1_MAX",
    "N_ID2_MAX",
    "Numerology",
    "PSS_SSS_FIRST",
    "RANGES",
    "SAMPLES_PER_SUBFRAME",
    "SAMPLE_RATE_HZ",
    "SEQ_LEN",
    "SLOTS_PER_SUBFRAME",
    "SSB_FIRST_K",
    "SSB_WIDTH",
    "SUBCARRIER_SPACING_HZ",
    "SYMBOLS_PER_SLOT",
    "SYMBOLS_PER_SUBFRAME",
    "ServingCell",
    "ServingRule",
    "band_bins",
    "burst_grid",
    "carrier_k",
    "kbin",
    "pci",
    "pss",
    "qpsk_pool",
    "reference_waveform",
    "ssb_first_symbols",
    "sss",
]
