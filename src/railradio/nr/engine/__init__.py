"""The nr burst engine: a scenario from the config, each epoch's burst synthesized once and read
by every receiver (the front end in one spectral pass, the correlations shared), and the per-
epoch estimates dataset; :mod:`railradio.nr.engine.equivalence` holds it to the reference path
of :mod:`railradio.nr.engine.simulate`.
"""

from railradio.nr.engine.epochs import PROGRESS_EVERY_S, shard_epochs, shard_period, simulate_epochs
from railradio.nr.engine.estimates_dataset import EpochRecord, estimates_dataset
from railradio.nr.engine.estimator import SharedEstimator
from railradio.nr.engine.frontend import SpectralSynthesis
from railradio.nr.engine.simulate import (
    Burst,
    EpochEstimates,
    Estimator,
    Scenario,
    Synthesis,
    calibration_trajectory,
    scenario_from_config,
)

__all__ = [
    "Burst",
    "EpochEstimates",
    "EpochRecord",
    "Estimator",
    "PROGRESS_EVERY_S",
    "Scenario",
    "SharedEstimator",
    "SpectralSynthesis",
    "Synthesis",
    "calibration_trajectory",
    "estimates_dataset",
    "scenario_from_config",
    "shard_epochs",
    "shard_period",
    "simulate_epochs",
]
