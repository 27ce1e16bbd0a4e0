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
    """File- and key-safe name of a variant, e.g. ``load_factor_0p3``, ``wslr_mean``.

    Parameters
    ----------
    switch : str
        The config key the variant changes, ``section.key``.
    value : Any
        The value the variant sets, in the key's own unit.

    Returns
    -------
    str
        ``<key>_<text>``: the key without its section, then ``str(value)`` with every ``.``
        written ``p`` and every ``-`` written ``m``.
    """
    short = switch.split(".")[-1]
    text = str(value).replace(".", "p").replace("-", "m")
    return f"{short}_{text}"


def variants(sens_cfg: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """``{"reference": {}, id: {"switch": "section.key", "value": v}, ...}`` in config order.

    Parameters
    ----------
    sens_cfg : dict
        The config's sensitivity section; ``switches`` maps ``"section.key"`` (section in
        :data:`~railradio.handover.params.SIM_SECTIONS`) to the list of values to try, in the
        key's own unit.

    Returns
    -------
    dict of str to dict
        Variant id (:func:`variant_id`, ``reference`` first) -> variant: ``{}`` for the
        reference, else ``{"switch": "section.key", "value": v}``.

    Raises
    ------
    ValueError
        If a switch is not ``section.key`` with a known section, or a variant id occurs twice.
    """
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
    """The scenario with the variant's switch set (ValueError from the dataclass if invalid).

    Parameters
    ----------
    scn : Scenario
        The reference scenario.
    variant : dict
        A variant of :func:`variants`: ``{}`` (the reference) or
        ``{"switch": "section.key", "value": v}``.

    Returns
    -------
    Scenario
        ``scn`` itself for the reference, else a copy with ``section.key = value``.

    Raises
    ------
    ValueError
        If the key is not a field of its section, or the value fails the section's checks.
    """
    if not variant:
        return scn
    section, key = variant["switch"].split(".")
    sub = getattr(scn, section)
    if not hasattr(sub, key):
        raise ValueError(f"unknown sensitivity switch {variant['switch']!r}")
    return replace(scn, **{section: replace(sub, **{key: variant["value"]})})


def affected_policies(variant: dict[str, Any], policies: tuple[str, ...]) -> tuple[str, ...]:
    """Policies whose outcome the variant can change (all for the reference).

    Parameters
    ----------
    variant : dict
        A variant of :func:`variants` (``{}`` for the reference).
    policies : tuple of str
        The policies of the study.

    Returns
    -------
    tuple of str
        Those of ``policies`` that :data:`AFFECTS` lists for the variant's section, in order.
    """
    if not variant:
        return tuple(policies)
    section = variant["switch"].split(".")[0]
    return tuple(p for p in policies if p in AFFECTS[section])
