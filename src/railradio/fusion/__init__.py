"""Study ``fusion``: TDOA/AOA fusion with the track as a constraint (source 002)."""

from railradio.fusion.crlb import crlb_rmse_m, fisher_information
from railradio.fusion.estimators import (
    aoa_on_track,
    aoa_variance_propagated,
    clip_to_segment,
    fuse,
    tdoa_on_track,
    tdoa_on_track_rootfind,
    tdoa_variance_propagated,
)
from railradio.fusion.geometry import CellGeometry
from railradio.fusion.montecarlo import ESTIMATORS, PointParams, simulate_point, summarize, sweep_dataset

__all__ = [
    "ESTIMATORS",
    "CellGeometry",
    "PointParams",
    "aoa_on_track",
    "aoa_variance_propagated",
    "clip_to_segment",
    "crlb_rmse_m",
    "fisher_information",
    "fuse",
    "simulate_point",
    "summarize",
    "sweep_dataset",
    "tdoa_on_track",
    "tdoa_on_track_rootfind",
    "tdoa_variance_propagated",
]
