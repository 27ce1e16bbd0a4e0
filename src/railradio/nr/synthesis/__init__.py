"""Received SS bursts: the band synthesis (source eq. 2–3), the full band's symbol edges that
complete it, the exact per-sample reference, and their compiled loops.
"""

from railradio.nr.synthesis.band_edges import BandEdges, SpectralBandEdges
from railradio.nr.synthesis.beams import at_train_mask, symbol_gains
from railradio.nr.synthesis.edge_math import N_NODES, N_POINTS, kappa
from railradio.nr.synthesis.edge_tables import ChebyshevEdges
from railradio.nr.synthesis.layout import BurstLayout
from railradio.nr.synthesis.reference import TAP_STEP_FULL, full_rate_noise, reference_correlation, reference_received
from railradio.nr.synthesis.spill import Spill
from railradio.nr.synthesis.synthesizer import DATA_BEAMS, Synthesizer

__all__ = [
    "BandEdges",
    "BurstLayout",
    "ChebyshevEdges",
    "DATA_BEAMS",
    "N_NODES",
    "N_POINTS",
    "SpectralBandEdges",
    "Spill",
    "Synthesizer",
    "TAP_STEP_FULL",
    "at_train_mask",
    "full_rate_noise",
    "kappa",
    "reference_correlation",
    "reference_received",
    "symbol_gains",
]
