"""The claim grids of the nr study: the reproduction map (figure ``nr_reproduction_map``)
and the source receiver's conditions (``nr_conditions``), from the map's key numbers
(:mod:`railradio.nr.study.reproduction_map`, :mod:`railradio.nr.study.conditions`)."""

from __future__ import annotations

import re

import numpy as np

from railradio import plotting
from railradio.nr.study.reproduction_map import CLAIMS, FAILS, HOLDS, SINGLE_CELL, STATUS_NAMES, UNRESOLVED

_STATUS_COLOURS = {HOLDS: "#9ecae1", UNRESOLVED: "#e8e8e8", FAILS: "#fdae6b"}  # blue / grey / orange


DATA_LABELS = {
    "others_random": "others at random beams",
    "all_train": "all beamed at the train",
    "serving_only": "serving cell only",
    "none": "none (PSS, SSS only)",
}
"""Readable names of the map's data assumptions (``nr.map.data``; another name is shown with
its underscores as spaces)."""

_MT_CELL = re.compile(r"^mt(\d+)_(.+)$")
_TPL_CELL = re.compile(r"^tpl_(.+)_sel_(.+)$")
_WIN_CELL = re.compile(r"^win(\d+)_(.+)$")


def cell_label(name: str) -> str:
    """A map cell's name as a figure or table shows it: ``mt32_others_random`` ->
    ``M_T = 32, data: others at random beams``; ``tpl_sss_sel_peak`` -> ``template SSS,
    selection: peak``; ``win2000_none`` -> ``window 2 km, data: none (PSS, SSS only)``; the sanity row
    ``single_none`` -> ``nearest RRH alone, data: none``.

    Parameters
    ----------
    name : str
        The cell's name (:func:`railradio.nr.study.reproduction_map.cells`).

    Returns
    -------
    str
        The label (the name itself when it follows neither pattern).
    """
    if m := _MT_CELL.match(name):
        data = DATA_LABELS.get(m.group(2), m.group(2).replace("_", " "))
        return f"M_T = {m.group(1)}, data: {data}"
    if m := _WIN_CELL.match(name):
        data = DATA_LABELS.get(m.group(2), m.group(2).replace("_", " "))
        return f"window {int(m.group(1)) / 1000:g} km, data: {data}"
    if m := _TPL_CELL.match(name):
        tpl = m.group(1).upper().replace("_", "+")
        return f"template {tpl}, selection: {m.group(2).replace('_', '-')}"
    if name == SINGLE_CELL:
        return "nearest RRH alone, data: none"
    return name


def plot_reproduction_map(numbers: dict, receivers: dict[str, list[str]], pdf: str, png: str) -> None:
    """The reproduction map (key numbers ``nr.map.<cell>.<tracker>.*``): one grid per
    tracker, a row per map cell and a column per source claim, each square coloured by
    the claim's status (holds / not resolved / fails) and labelled with the measured value
    (its bootstrap interval in the key numbers); a lost tracker is labelled with its lost
    share.

    Parameters
    ----------
    numbers : dict
        Key numbers (name -> entry with ``value``, optional ``lost_frac``),
        :func:`railradio.nr.study.reproduction_map.cell_key_numbers` and ``summary_key_numbers``.
    receivers : dict of str to list of str
        Tracker name -> the map cells it ran on (rows), :func:`railradio.nr.study.reproduction_map.cell_receivers`.
    pdf : str
        Path of the PDF figure.
    png : str
        Path of the PNG copy.

    Raises
    ------
    KeyError
        When a cell's claim or metric key is missing from ``numbers``.
    """
    titles = {"source": "source's receiver (no gate)", "source_gated": "source's receiver, gated"}
    names = list(receivers)
    height = 0.3 * max(len(receivers[r]) for r in names) + 2.0
    fig, axes = plotting.figure(ncols=len(names), figsize=(6.4 * len(names), height), squeeze=False)
    for ax, rx in zip(axes[0], names, strict=True):
        _claim_grid(ax, numbers, [(f"nr.map.{c}.{rx}", cell_label(c)) for c in receivers[rx]], interval=False)
        ax.set_title(titles.get(rx, f"our receiver ({rx}, gated)"), fontsize=9)
    _status_legend(fig)
    fig.subplots_adjust(left=0.14 / max(1, len(names) - 1), bottom=1.5 / height, top=1 - 0.35 / height, wspace=0.75)
    plotting.save(fig, pdf, png)


def plot_conditions(
    numbers: dict,
    rows: list[tuple[str, str]],
    smallest: dict[str, list[str]],
    pdf: str,
    png: str,
    sanity: list[tuple[str, str]] | None = None,
    partial: set[str] | None = None,
):
    """The source receiver's conditions: a row per condition (window × gate × data), a
    column per source claim, each square coloured by the claim's status there and labelled
    with the measured value and its bootstrap interval; under them the sanity rows, set
    apart; under each claim, the fewest departures (bounded window, gate) under which it
    holds.

    Parameters
    ----------
    numbers : dict
        The map's key numbers with :func:`railradio.nr.study.conditions.key_numbers`.
    rows : list of (str, str)
        Per condition its key prefix ``nr.map.<cell>.<tracker>`` and its label, in the
        order of :func:`railradio.nr.study.conditions.conditions`.
    smallest : dict of str to list of str
        Claim -> the prefixes of its smallest set of conditions (framed).
    pdf, png : str
        Paths of the PDF figure and its PNG copy.
    sanity : list of (str, str), optional
        The sanity row's trackers (:func:`railradio.nr.study.conditions.sanity_rows`), drawn
        below a rule.
    partial : set of str, optional
        Prefixes of rows with some claims only (the sanity row's own measurements,
        :func:`railradio.nr.study.conditions.partial_rows`): their other squares stay blank.

    Raises
    ------
    KeyError
        When a condition's claim or metric key is missing from ``numbers``.
    """
    from matplotlib.patches import Rectangle

    grid = rows + list(sanity or [])
    height = 0.42 * len(grid) + 2.4
    fig, ax = plotting.figure(figsize=(7.6, height))
    _claim_grid(ax, numbers, grid, interval=True, partial=frozenset(partial or ()))
    if sanity:
        ax.axhline(len(rows), color="black", linewidth=1.6)
    prefixes = [p for p, _ in rows]
    for j, cname in enumerate(CLAIMS):
        for p in smallest.get(cname, []):
            ax.add_patch(Rectangle((j, prefixes.index(p)), 1, 1, fill=False, edgecolor="black", linewidth=1.4))
        d = numbers[f"nr.map.conditions.{cname}.min_departures"]["value"]
        ax.text(j + 0.5, len(grid) + 0.45, "never" if d is None else f"{d:.0f}", ha="center", va="center", fontsize=7)
    ax.set_ylim(len(grid) + 0.9, 0)
    ax.set_title("source's receiver: fewest departures under which each claim holds (framed; bottom row)", fontsize=8)
    _status_legend(fig)
    fig.subplots_adjust(left=0.36, bottom=1.6 / height, top=1 - 0.35 / height)
    plotting.save(fig, pdf, png)


def _claim_grid(
    ax, numbers: dict, rows: list[tuple[str, str]], interval: bool, partial: frozenset[str] = frozenset()
) -> None:
    """Squares of a claim grid on ``ax``: row i is the key prefix ``rows[i][0]`` (labelled
    ``rows[i][1]``), column j the claim j of ``CLAIMS``; ``interval``: the bootstrap
    interval under each value. A row whose prefix is in ``partial`` leaves the claims it has
    no status for blank; any other missing status raises KeyError."""
    for i, (p, _) in enumerate(rows):
        for j, (cname, claim) in enumerate(CLAIMS.items()):
            if p in partial and f"{p}.claim.{cname}" not in numbers:
                continue  # a row with some claims only (the sanity row's measurements): blank
            st = numbers[f"{p}.claim.{cname}"]["value"]
            e = numbers[f"{p}.{claim.metric}"]
            text = _claim_text(e, claim.unit)
            lo, hi = (numbers.get(f"{p}.{claim.metric}.{end}", {}).get("value") for end in ("lo", "hi"))
            if interval and e["value"] is not None and lo is not None and hi is not None:
                text += f"\n[{_claim_text({'value': lo}, claim.unit)}, {_claim_text({'value': hi}, claim.unit)}]"
            ax.add_patch(_square(j, i, _STATUS_COLOURS[st]))
            ax.text(j + 0.5, i + 0.5, text, ha="center", va="center", fontsize=5.5, linespacing=0.9)
    ax.set_xlim(0, len(CLAIMS))
    ax.set_ylim(len(rows), 0)
    ax.set_xticks(np.arange(len(CLAIMS)) + 0.5)
    ax.set_xticklabels([c.label for c in CLAIMS.values()], rotation=45, ha="right", fontsize=7)
    ax.set_yticks(np.arange(len(rows)) + 0.5)
    ax.set_yticklabels([label for _, label in rows], fontsize=6.5)
    ax.tick_params(length=0)
    ax.grid(False)


def _claim_text(e: dict, unit: str) -> str:
    """A claim metric's value as a square shows it (a lost tracker: its lost share)."""
    if e["value"] is None and e.get("lost_frac"):
        return f"lost\n{100 * e['lost_frac']:.0f}%"
    if e["value"] is None:
        return "--"
    if unit == "1":
        return f"{100 * e['value']:.0f}%"
    return f"{e['value']:.2g}" if abs(e["value"]) < 10 else f"{e['value']:.0f}"


def _status_legend(fig) -> None:
    """The claim grids' legend: holds / not resolved / fails."""
    from matplotlib.patches import Patch

    fig.legend(
        handles=[Patch(facecolor=_STATUS_COLOURS[s], label=STATUS_NAMES[s]) for s in (HOLDS, UNRESOLVED, FAILS)],
        loc="lower center",
        ncol=3,
        fontsize=7,
        frameon=False,
        bbox_to_anchor=(0.5, 0.0),
    )


def _square(x: float, y: float, colour: str):
    """A unit square of the map at (x, y)."""
    from matplotlib.patches import Rectangle

    return Rectangle((x, y), 1, 1, facecolor=colour, edgecolor="white", linewidth=1.0)
