"""One-at-a-time sensitivity cases of the uncertain reconstruction choices.

Each case changes one switch of the scenario (``section.key`` → value) and is run on
the same random draws as the reference (common random numbers), so a difference is the
switch's effect.  The joint weights (m, α) stay the cost grid's argmin for the case's
WSLR reading.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from railradio.handover.params import SIM_SECTIONS, Scenario

AFFECTS = {
    "joint": ("joint",),
    "a3": ("a3",),
    "a3_rail": ("a3_rail",),
    "radio": ("joint", "a3", "a3_rail", "distance"),
    "train": ("joint", "a3", "a3_rail", "distance"),
    "execution": ("joint", "a3", "a3_rail", "distance"),
}
"""Policies a switch of each scenario section can change."""


def case_id(switch: str, value: Any) -> str:
    """File- and key-safe name of a case, e.g. ``load_factor_0p3``, ``wslr_mean``.

    Parameters
    ----------
    switch : str
        The config key the case changes, ``section.key``.
    value : Any
        The value the case sets, in the key's own unit.

    Returns
    -------
    str
        ``<key>_<text>``: the key without its section, then ``str(value)`` with every ``.``
        written ``p`` and every ``-`` written ``m``.
    """
    short = switch.split(".")[-1]
    text = str(value).replace(".", "p").replace("-", "m")
    return f"{short}_{text}"


def cases(sens_cfg: dict[str, Any]) -> dict[str, dict[str, Any]]:
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
        Case id (:func:`case_id`, ``reference`` first) -> case: ``{}`` for the
        reference, else ``{"switch": "section.key", "value": v}``.

    Raises
    ------
    ValueError
        If a switch is not ``section.key`` with a known section, or a case id occurs twice.
    """
    out: dict[str, dict[str, Any]] = {"reference": {}}
    for switch, values in sens_cfg.get("switches", {}).items():
        section = switch.split(".")[0]
        if section not in SIM_SECTIONS or switch.count(".") != 1:
            raise ValueError(f"sensitivity switch must be 'section.key' with section in {SIM_SECTIONS}, got {switch!r}")
        for v in values:
            cid = case_id(switch, v)
            if cid in out:
                raise ValueError(f"sensitivity case {cid!r} defined twice")
            out[cid] = {"switch": switch, "value": v}
    return out


def apply_case(scn: Scenario, case: dict[str, Any]) -> Scenario:
    """The scenario with the case's switch set (ValueError from the dataclass if invalid).

    Parameters
    ----------
    scn : Scenario
        The reference scenario.
    case : dict
        A case of :func:`cases`: ``{}`` (the reference) or
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
    if not case:
        return scn
    section, key = case["switch"].split(".")
    sub = getattr(scn, section)
    if not hasattr(sub, key):
        raise ValueError(f"unknown sensitivity switch {case['switch']!r}")
    return replace(scn, **{section: replace(sub, **{key: case["value"]})})


def affected_policies(case: dict[str, Any], policies: tuple[str, ...]) -> tuple[str, ...]:
    """Policies whose outcome the case can change (all for the reference).

    Parameters
    ----------
    case : dict
        A case of :func:`cases` (``{}`` for the reference).
    policies : tuple of str
        The policies of the study.

    Returns
    -------
    tuple of str
        Those of ``policies`` that :data:`AFFECTS` lists for the case's section, in order.
    """
    if not case:
        return tuple(policies)
    section = case["switch"].split(".")[0]
    return tuple(p for p in policies if p in AFFECTS[section])
