"""The source receiver's conditions: under which of them each source claim holds
(config/README.md ``nr.map.conditions``, docs/model/nr.md §9).

The source does not say how wide its receiver searches beyond eq. 5's K lags (the SS-block
spacing), whether its EKF rejects outliers, where the data traffic is beamed, nor which W
and Q it used (it gives the model, eq. 11, and no value). A **condition** fixes three of
these on the main run's bursts (its M_T) and its receiver (μ + 4σ, PSS+SSS template, the
cell search's SS-RSRP selection):

* the search window: the source's K, or a window bounded by the geometry (delays up to
  ``map.conditions.windows_m``; the receiver's ``search_range_m``);
* the gate: none (the source's EKF), or our χ² gate at ``nr.tracker.gate_prob`` with its
  re-initialisation;
* the data assumption (``map.conditions.data``).

W and q have one level, ours (the calibration run's robust W and the NEES q): the source
gives no value to hold them at (the q band, ``study/q_band.py``, shows how far the headline
moves with q).

A condition is a map cell and one of its trackers (``mt<M>_<data>`` for K,
``win<m>_<data>`` for a bounded window; tracker ``source`` or ``source_gated``), so each
claim's status there is the map's: its block-bootstrap interval wholly on the claim's side
(holds), wholly on the other (fails), or neither (not resolved). A condition's
**departures** are the changes to the source's receiver and tracker it makes — a bounded
window, the gate — 0 to 2; the data are an assumption the source leaves open, not a
departure. For each claim, the **smallest set of conditions** under which it holds are those
with the fewest departures among the conditions where it holds.

The **sanity row** (``map.conditions.single_rrh``, cell
:data:`railradio.nr.study.reproduction_map.SINGLE_CELL`) is not a condition on the main run's
deployment: the nearest RRH alone in range and no data, so no interference at all, with the
source's K, tracked ungated and gated. The receiver's measurements of that one RRH
(``diag.nearest.*``) are its accuracy without interference: an accuracy it misses there it
misses with interference added. Its claims on the three RRHs it selects are not easier there
(with one RRH audible the selection takes what the detector finds in the noise), nor are the
tracking claims, which lean on the selected measurements.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from railradio.keynumbers import KeySpec
from railradio.nr.study.reproduction_map import CLAIMS, FAILS, GATED, HOLDS, SINGLE_CELL, window_cell


@dataclass(frozen=True)
class Condition:
    """One condition of the source's receiver (see the module's description)."""

    window_m: float | None
    """Search window [m]; None: the source's K (the SS-block spacing, source eq. 5)."""
    gated: bool
    """Whether the tracker gates (our χ² gate) or not (the source's EKF)."""
    data: str
    """The data assumption (a key of ``nr.map.data``)."""
    m_t: int
    """Tx elements per RRH panel (the main run's)."""

    @property
    def cell(self) -> str:
        """The map cell holding this condition's bursts and estimates."""
        return f"mt{self.m_t}_{self.data}" if self.window_m is None else window_cell(self.window_m, self.data)

    @property
    def tracker(self) -> str:
        """The map tracker: ``source`` (no gate) or ``source_gated``."""
        return f"source{GATED}" if self.gated else "source"

    @property
    def departures(self) -> int:
        """Changes to the source's receiver and tracker: a bounded window, the gate."""
        return int(self.window_m is not None) + int(self.gated)

    @property
    def prefix(self) -> str:
        """Its key numbers' prefix in the map: ``nr.map.<cell>.<tracker>``."""
        return f"nr.map.{self.cell}.{self.tracker}"

    def label(self, data_labels: dict[str, str] | None = None) -> str:
        """``window K, no gate, data: <data>`` / ``window 2 km, gated, ...``."""
        w = "K" if self.window_m is None else f"{self.window_m / 1000:g} km"
        d = (data_labels or {}).get(self.data, self.data.replace("_", " "))
        return f"window {w}, {'gated' if self.gated else 'no gate'}, data: {d}"


def conditions(nr: dict) -> list[Condition]:
    """Every condition of the map's config, by departures, then window (K first, then
    ``windows_m`` in config order), gate (off first) and data (``conditions.data`` order).

    Parameters
    ----------
    nr : dict
        The ``nr`` section of the workflow config (with its ``map`` section).

    Returns
    -------
    list of Condition
        The conditions; the first is the source's literal setting under the first data assumption.

    Raises
    ------
    ValueError
        When a data assumption of ``map.conditions`` is not a key of ``map.data``.
    """
    cond = nr["map"].get("conditions", {})
    data = list(cond.get("data", []))
    unknown = [d for d in data if d not in nr["map"]["data"]]
    if unknown:
        raise ValueError(f"nr.map.conditions.data must be keys of nr.map.data, got {unknown!r}")
    windows: list[float | None] = [None, *(float(w) for w in cond.get("windows_m", []))]
    m_t = int(nr["antenna"]["rrh_elements"])
    out = [Condition(w, g, d, m_t) for w in windows for g in (False, True) for d in data]
    return sorted(out, key=lambda c: c.departures)  # stable: the axes' order within


def key_numbers(numbers: dict[str, Any], nr: dict) -> dict[str, Any]:
    """Per source claim, the conditions under which it holds: ``nr.map.conditions.<claim>.
    min_departures`` (the fewest departures among them; null: it holds under none),
    ``.n_holds`` and ``.n_fails`` (of ``nr.map.conditions.n``), and per condition and claim
    nothing new (the status is the map's key ``<prefix>.claim.<claim>``).

    Parameters
    ----------
    numbers : dict
        The map's key numbers (:func:`railradio.nr.study.reproduction_map.cell_key_numbers`
        of every condition's cell and tracker).
    nr : dict
        The ``nr`` section of the workflow config.

    Returns
    -------
    dict of str to dict
        Key name -> its JSON entry (:meth:`railradio.keynumbers.KeySpec.entry`).

    Raises
    ------
    KeyError
        When a condition's claim status is missing from ``numbers``.
    """
    conds = conditions(nr)
    least = smallest(numbers, nr)
    out: dict[str, Any] = {
        "nr.map.conditions.n": KeySpec(
            "nr.map.conditions.n", "1", "conditions of the source's receiver (window x gate x data)"
        ).entry(float(len(conds)))
    }
    for cname, claim in CLAIMS.items():
        st = [numbers[f"{c.prefix}.claim.{cname}"]["value"] for c in conds]
        p = f"nr.map.conditions.{cname}"
        out[f"{p}.min_departures"] = KeySpec(
            f"{p}.min_departures",
            "1",
            f"fewest departures (bounded window, gate) of the source's receiver under which '{claim.label}' "
            "holds (null: under none)",
        ).entry(float(least[cname][0].departures) if least[cname] else None)
        for code, word in ((HOLDS, "holds"), (FAILS, "fails")):
            out[f"{p}.n_{word}"] = KeySpec(
                f"{p}.n_{word}", "1", f"conditions of the source's receiver under which '{claim.label}' {word}"
            ).entry(float(sum(s == code for s in st)))
    return out


def smallest(numbers: dict[str, Any], nr: dict) -> dict[str, list[Condition]]:
    """Per claim, the conditions with the fewest departures under which it holds (empty:
    it holds under none).

    Parameters
    ----------
    numbers : dict
        The map's key numbers.
    nr : dict
        The ``nr`` section of the workflow config.

    Returns
    -------
    dict of str to list of Condition
        Claim name (:data:`railradio.nr.study.reproduction_map.CLAIMS`) -> conditions.
    """
    conds, out = conditions(nr), {}
    for cname in CLAIMS:
        ok = [c for c in conds if numbers[f"{c.prefix}.claim.{cname}"]["value"] == HOLDS]
        out[cname] = [c for c in ok if c.departures == ok[0].departures]  # sorted by departures
    return out


def sanity_rows(nr: dict) -> list[tuple[str, str]]:
    """The sanity row's trackers of the source's receiver (none when
    ``map.conditions.single_rrh`` is off), ungated first, then its measurements of the one
    RRH in range (the measurement claims only, ``diag.nearest``): key prefix and label each.

    Parameters
    ----------
    nr : dict
        The ``nr`` section of the workflow config (with its ``map`` section).

    Returns
    -------
    list of (str, str)
        ``(nr.map.<SINGLE_CELL>.<tracker>, label)`` for the trackers ``source`` and
        ``source_gated``, then ``(nr.map.<SINGLE_CELL>.source.diag.nearest, label)``.
    """
    if not nr["map"].get("conditions", {}).get("single_rrh", False):
        return []
    p = f"nr.map.{SINGLE_CELL}.source"
    trackers = [
        (f"{p}{GATED if gated else ''}", f"nearest RRH alone, window K, {'gated' if gated else 'no gate'}, data: none")
        for gated in (False, True)
    ]
    return trackers + [(f"{p}.diag.nearest", "nearest RRH alone: its own AOD and TOA (whatever is selected)")]


def partial_rows(nr: dict) -> set[str]:
    """The prefixes of :func:`sanity_rows` that hold the measurement claims only (the
    receiver's own measurements of the one RRH in range, ``diag.nearest``).

    Parameters
    ----------
    nr : dict
        The ``nr`` section of the workflow config (with its ``map`` section).

    Returns
    -------
    set of str
        The prefixes (empty when ``map.conditions.single_rrh`` is off).
    """
    return {p for p, _ in sanity_rows(nr) if p.endswith(".diag.nearest")}
