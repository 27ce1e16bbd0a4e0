"""The train's receiver: its configuration, the front end between sample rates, the source's
correlation receiver (source eq. 4–9), the cell search, and every receiver of an epoch on one
shared set of correlations.
"""

from railradio.nr.receiver.cellsearch import (
    CellSearch,
    CellSearchConfig,
    correlation_key,
    neighbour_list,
    ss_rsrp_db,
    warmup_start,
)
from railradio.nr.receiver.config import ReceiverConfig, fft_rows
from railradio.nr.receiver.correlator import (
    CA_GUARD_FULL,
    CA_PRESCREEN,
    CA_WINDOW_FULL,
    DETECTORS,
    BlockCorrelation,
    Correlator,
    cfar_threshold,
    detection_levels,
)
from railradio.nr.receiver.frontend import front_end, project, upsample
from railradio.nr.receiver.shared import SharedCorrelation

__all__ = [
    "BlockCorrelation",
    "CA_GUARD_FULL",
    "CA_PRESCREEN",
    "CA_WINDOW_FULL",
    "CellSearch",
    "CellSearchConfig",
    "Correlator",
    "DETECTORS",
    "ReceiverConfig",
    "SharedCorrelation",
    "cfar_threshold",
    "correlation_key",
    "detection_levels",
    "fft_rows",
    "front_end",
    "neighbour_list",
    "project",
    "ss_rsrp_db",
    "upsample",
    "warmup_start",
]
