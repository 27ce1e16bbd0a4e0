"""Study `handover`: position-power joint handover decision against A3 and distance
triggers (source 004).  The model is OUR reconstruction of the source's lost equations,
stated in docs/model/handover.md; every uncertain choice is a config switch."""

from railradio.handover.params import A3, Execution, Joint, Radio, Scenario, Train, scenario_from_config
from railradio.handover.policies import POLICIES, Policy, make_policy, register, run_policy

__all__ = [
    "A3",
    "POLICIES",
    "Execution",
    "Joint",
    "Policy",
    "Radio",
    "Scenario",
    "Train",
    "make_policy",
    "register",
    "run_policy",
    "scenario_from_config",
]
