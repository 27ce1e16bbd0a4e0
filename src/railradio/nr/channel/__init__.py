"""From each RRH to the train: deployment and trajectory, antenna patterns, path loss, shadowing
and TDL fading (TR 38.901), the link budget per epoch, the links' geometry over a burst, and
the clocks' offsets.
"""

from railradio.nr.channel.antenna import (
    ARRAY_NULL_FLOOR,
    ELEMENT_FRONT_BACK_DB,
    ELEMENT_HPBW_DEG,
    ELEMENT_MAX_GAIN_DBI,
    RrhArray,
    TrainArray,
    element_gain_db,
    facing_panel,
    ula_gain,
    wrap_rad,
)
from railradio.nr.channel.clocks import KEY_SYNC, apply_clock_errors, clock_offsets_s
from railradio.nr.channel.geometry import Deployment, Trajectory
from railradio.nr.channel.link import BOLTZMANN_DBM_HZ, LinkBudget, Links, RadioParams, ShadowingMap, link_budget
from railradio.nr.channel.motion import BurstMotion, burst_motion
from railradio.nr.channel.tdl import (
    TdlProfile,
    breakpoint_distance_m,
    pathloss_umi_los_db,
    shadowing_field_db,
    sos_eval,
    sos_params,
    sos_taps,
    tdl_profile,
)

__all__ = [
    "ARRAY_NULL_FLOOR",
    "BOLTZMANN_DBM_HZ",
    "BurstMotion",
    "Deployment",
    "ELEMENT_FRONT_BACK_DB",
    "ELEMENT_HPBW_DEG",
    "ELEMENT_MAX_GAIN_DBI",
    "KEY_SYNC",
    "LinkBudget",
    "Links",
    "RadioParams",
    "RrhArray",
    "ShadowingMap",
    "TdlProfile",
    "TrainArray",
    "Trajectory",
    "apply_clock_errors",
    "breakpoint_distance_m",
    "burst_motion",
    "clock_offsets_s",
    "element_gain_db",
    "facing_panel",
    "link_budget",
    "pathloss_umi_los_db",
    "shadowing_field_db",
    "sos_eval",
    "sos_params",
    "sos_taps",
    "tdl_profile",
    "ula_gain",
    "wrap_rad",
]
