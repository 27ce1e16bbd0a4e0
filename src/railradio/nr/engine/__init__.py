"""The nr burst engine: each correlation computed once for every receiver of an epoch, and
the receiver's front end in one spectral pass. The study runs it
(:func:`railradio.nr.epochs.simulate_epochs`); :mod:`railradio.nr.engine.equivalence`,
``make bench`` and the fidelity target (:func:`railradio.nr.fidelity.check_production`) hold
it to the reference path of :mod:`railradio.nr.simulate` on the same bursts.
"""

from railradio.nr.engine.correlation import SharedCorrelation
from railradio.nr.engine.estimator import SharedEstimator
from railradio.nr.engine.frontend import SpectralBandEdges, SpectralSynthesis, front_end

__all__ = ["SharedCorrelation", "SharedEstimator", "SpectralBandEdges", "SpectralSynthesis", "front_end"]
