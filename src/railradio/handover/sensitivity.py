"""One-at-a-time sensitivity variants of the uncertain reconstruction choices.

Each variant changes one switch of the scenario (``section.key`` → value) and is run on
the same random draws as the reference (common random numbers), so a difference is the
switch's effect.  The joint weights (m, α) stay the cost grid's argmin for the variant's
WSLR reading.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from railradio.handover.params import SIM_SECTIONS, Scenario

AFFECTS = {
    "joint": ("joint",),
    "a3": ("a3",),
    "radio": ("joint", "a3", "distance"),
    "train": ("joint", "a3", "distance"),
    "execution": ("joint", "a3", "distance"),
}
"""Policies a switch of each scenario section can change."""


def variant_id(switch: str, value: Any) -> str:
    """File- and key-safe name of a variant, e.g. ``load_factor_0p3``, ``wslr_mean``."""
    short = switch.split(".")[-1]
    text = str(value).replace(".", "p").replace("-", "m")
    return f"{short}_{text}"


def variants(sens_cfg: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """``{"reference": {}, id: {"switch": "section.key", "value": v}, ...}`` in config order."""
    out: dict[str, dict[str, Any]] = {"reference": {}}
    for switch, values in sens_cfg.get("switches", {}).items():
        section = switch.split(".")[0]
        if section not in SIM_SECTIONS or switch.count(".") != 1:
            raise ValueError(f"sensitivity switch must be 'section.key' with section in {SIM_SECTIONS}, got {switch!r}")
        for v in values:
            vid = variant_id(switch, v)
            if vid in out:
                raise ValueError(f"sensitivity variant {vid!r} defined twice")
            out[vid] = {"switch": switch, "value": v}
    return out


def apply_variant(scn: Scenario, variant: dict[str, Any]) -> Scenario:
    """The scenario with the variant's switch set (ValueError from the dataclass if invalid)."""
    if not variant:
        return scn
    section, key = variant["switch"].split(".")
    sub = getattr(scn, section)
    if not hasattr(sub, key):
        raise ValueError(f"unknown sensitivity switch {variant['switch']!r}")
    return replace(scn, **{section: replace(sub, **{key: variant["value"]})})


def affected_policies(variant: dict[str, Any], policies: tuple[str, ...]) -> tuple[str, ...]:
    """Policies whose outcome the variant can change (all for the reference)."""
    if not variant:
        return tuple(policies)
    section = variant["switch"].split(".")[0]
    return tuple(p for p in policies if p in AFFECTS[section])
