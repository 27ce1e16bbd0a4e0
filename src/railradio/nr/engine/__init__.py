"""The nr burst engine (being built): each correlation computed once for every receiver of an
epoch, and the receiver's front end in one spectral pass. Not yet in the pipeline: the study
runs :mod:`railradio.nr.simulate`; ``make bench`` and :mod:`railradio.nr.engine.equivalence`
measure this engine against it on the same bursts.
"""

from railradio.nr.engine.correlation import SharedCorrelation
from railradio.nr.engine.estimator import SharedEstimator
from railradio.nr.engine.frontend import SpectralBandEdges, SpectralSynthesis, front_end

__all__ = ["SharedCorrelation", "SharedEstimator", "SpectralBandEdges", "SpectralSynthesis", "front_end"]
