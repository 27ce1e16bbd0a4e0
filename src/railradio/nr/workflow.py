"""The nr config as the workflow's rules see it (kept out of the simulation code's
fingerprint: a change here re-runs nothing by itself)."""

from __future__ import annotations

SIM_KEYS = ("trajectory", "deployment", "radio", "antenna", "channel", "receiver",
            "receiver_variants", "traffic")
"""The sections of the ``nr`` config that define the simulated bursts."""


def sim_config(c: dict) -> dict:
    """The simulation-defining sections of an ``nr`` config (a rule's params)."""
    return {k: c[k] for k in SIM_KEYS if k in c}


def receiver_selection(c: dict) -> dict[str, str]:
    """Receiver name -> the strength measure choosing its 3 measured RRHs."""
    return {"seed": c["receiver"]["selection"]} | {
        name: v["selection"] for name, v in c.get("receiver_variants", {}).items()}
