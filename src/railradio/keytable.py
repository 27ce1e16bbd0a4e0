"""The key numbers as data: a tidy table (one row a key, CSV) and a digest by study
(``docs/keys.md``), each claim of a source paper with a verdict.

The verdict of a key whose source paper states a value, by a rule fixed before reading any
result (``config/README.md``, "verdicts"):

* the source's ``<``, ``≤``, ``>``, ``≥`` — a bound the source claims its quantity meets:
  ``holds`` when ours meets it by more than 2 Monte Carlo standard errors (by any margin when
  the key has none), ``fails`` when ours misses it by more than that, else ``undecided``;
* the source's ``=`` and ``≈`` — a value it reports, to the digits it prints: ``agrees`` when
  ours lies within half a unit of the source's last printed digit plus 2 standard errors,
  else ``ours lower`` or ``ours higher``;
* ``no value`` when we have none (a lost track: the key's ``lost_frac`` says how much).

    python -m railradio.keytable csv paper/numbers.json results/key_numbers.csv
    python -m railradio.keytable docs paper/numbers.json docs/keys.md
"""

from __future__ import annotations

import csv
import io
import json
import math
import re
import sys
from collections.abc import Mapping
from decimal import Decimal
from typing import Any

COLUMNS = (
    "key",
    "study",
    "value",
    "unit",
    "mc_stderr",
    "lost_frac",
    "source_value",
    "source_relation",
    "verdict",
    "description",
)
"""The CSV's columns, in order."""

N_SE = 2.0
"""Monte Carlo standard errors a verdict allows (≈ a 95 % two-sided interval)."""


def study_of(key: str) -> str:
    """The study a key belongs to: its first segment (``sens.<study>.…``: the study's
    sensitivity cases, ``<study>``)."""
    parts = key.split(".")
    return parts[1] if parts[0] == "sens" and len(parts) > 1 else parts[0]


def half_unit(source_value: float) -> float:
    """Half a unit of the last digit the source prints, from the value's shortest decimal form
    (an integer: 0.5; 0.66: 0.005; 3.5 and 8.0: 0.05)."""
    if isinstance(source_value, int):
        return 0.5
    exponent = Decimal(repr(float(source_value))).as_tuple().exponent
    return 0.5 * 10.0 ** int(exponent)


def verdict(e: Mapping[str, Any]) -> str:
    """The verdict of one key-number entry on its source claim ('' when there is none).

    Parameters
    ----------
    e : mapping
        A key-number entry: ``value``, ``mc_stderr``, ``source_value``, ``source_relation``.

    Returns
    -------
    str
        ``holds``, ``fails``, ``undecided``, ``agrees``, ``ours lower``, ``ours higher``,
        ``no value`` or ``''``.

    Raises
    ------
    ValueError
        When ``source_relation`` is not one of the relations of :mod:`railradio.keynumbers`.
    """
    src, rel = e.get("source_value"), e.get("source_relation")
    if src is None or rel is None:
        return ""
    v = e.get("value")
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "no value"
    margin = N_SE * float(e.get("mc_stderr") or 0.0)
    if rel in ("<", "≤", ">", "≥"):
        gap = (src - v) if rel in ("<", "≤") else (v - src)  # > 0: the claim is met
        strict = rel in ("<", ">")
        if gap > margin or (margin == 0.0 and (gap > 0 or (gap == 0 and not strict))):
            return "holds"
        return "fails" if -gap >= margin else "undecided"
    if rel in ("=", "≈"):
        if abs(v - src) <= half_unit(src) + margin:
            return "agrees"
        return "ours lower" if v < src else "ours higher"
    raise ValueError(f"source_relation must be one of <, ≤, >, ≥, =, ≈, got {rel!r}")


def rows(numbers: Mapping[str, Mapping[str, Any]]) -> list[dict[str, Any]]:
    """One row a key (:data:`COLUMNS`), sorted by key."""
    out = []
    for key in sorted(numbers):
        e = numbers[key]
        out.append(
            {
                "key": key,
                "study": study_of(key),
                "value": e.get("value"),
                "unit": e.get("unit", ""),
                "mc_stderr": e.get("mc_stderr"),
                "lost_frac": e.get("lost_frac"),
                "source_value": e.get("source_value"),
                "source_relation": e.get("source_relation"),
                "verdict": verdict(e),
                "description": e.get("description", ""),
            }
        )
    return out


def to_csv(numbers: Mapping[str, Mapping[str, Any]]) -> str:
    """The tidy table as CSV text (empty cells where a key has no such value)."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=COLUMNS, lineterminator="\n")
    w.writeheader()
    for r in rows(numbers):
        w.writerow({k: ("" if r[k] is None else r[k]) for k in COLUMNS})
    return buf.getvalue()


VERDICT_GROUPS = {
    "met": ("holds", "agrees"),
    "not met": ("fails", "ours lower", "ours higher"),
    "undecided": ("undecided", "no value"),
}
"""How the appendix's per-study summary groups the verdicts of :func:`verdict`."""


def study_summary(numbers: Mapping[str, Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Per study, in order of first appearance: the number of keys, of keys with a source
    value, and of those whose claim is met, not met or undecided (:data:`VERDICT_GROUPS`).

    Parameters
    ----------
    numbers : mapping
        Key name -> key-number entry (``value``, ``mc_stderr``, ``source_value``,
        ``source_relation``).

    Returns
    -------
    list of dict
        ``study``, ``keys``, ``claims``, ``met``, ``not met``, ``undecided`` [1].
    """
    out: dict[str, dict[str, Any]] = {}
    for key, e in numbers.items():
        st = study_of(key)
        row = out.setdefault(st, {"study": st, "keys": 0, "claims": 0, **dict.fromkeys(VERDICT_GROUPS, 0)})
        row["keys"] += 1
        v = verdict(e)
        if not v:
            continue
        row["claims"] += 1
        row[next(g for g, vs in VERDICT_GROUPS.items() if v in vs)] += 1
    return list(out.values())


def study_summary_latex(numbers: Mapping[str, Mapping[str, Any]]) -> str:
    """:func:`study_summary` as a LaTeX (booktabs) table body in a ``tabular``."""
    lines = [
        r"\begin{tabular}{@{}lrrrrr@{}}",
        r"\toprule",
        r"study & key numbers & with a source value & met & not met & undecided\\",
        r"\midrule",
    ]
    for r in study_summary(numbers):
        cells = [r["study"], r["keys"], r["claims"], r["met"], r["not met"], r["undecided"]]
        lines.append(" & ".join(str(c) for c in cells) + r" \\")
    lines += [r"\bottomrule", r"\end{tabular}"]
    return "\n".join(lines) + "\n"


_CELL = re.compile(r"^(nr\.map\.)(?:mt\d+|tpl)_[^.]+\.")
_CASE = re.compile(r"^((?:sens\.\w+|\w+\.sens)\.)[^.]+\.")


def _family(key: str) -> str:
    """A key with what varies between its siblings folded: the reproduction map's cell
    (``<cell>``), a sensitivity case (``<case>``), and every run of digits (speeds, sweep
    points, percentiles: ``*``)."""
    key = _CELL.sub(r"\1<cell>.", key)
    key = _CASE.sub(r"\1<case>.", key)
    return re.sub(r"\d+(?:_\d+)*", "*", key)


def markdown(numbers: Mapping[str, Mapping[str, Any]], source: str = "paper/numbers.json") -> str:
    """``docs/keys.md``: per study, its claims with their verdicts and its key families."""
    by_study: dict[str, list[dict[str, Any]]] = {}
    for r in rows(numbers):
        by_study.setdefault(r["study"], []).append(r)
    out = [
        "# The key numbers, by study",
        "",
        f"Generated from `{source}` by `python -m railradio.keytable docs {source} docs/keys.md`",
        "(a test fails when it is not current). Every key as a table: `results/key_numbers.csv`",
        "(`make numbers`; columns: " + ", ".join(f"`{c}`" for c in COLUMNS) + "). The verdict rule:",
        "`railradio.keytable` and `config/README.md`.",
        "",
        "| study | keys | beside a source claim | holds / agrees | fails / differs | undecided / no value |",
        "|---|---|---|---|---|---|",
    ]
    good, bad = ("holds", "agrees"), ("fails", "ours lower", "ours higher")
    for study, rs in by_study.items():
        claims = [r for r in rs if r["verdict"]]
        n_good = sum(r["verdict"] in good for r in claims)
        n_bad = sum(r["verdict"] in bad for r in claims)
        out.append(f"| {study} | {len(rs)} | {len(claims)} | {n_good} | {n_bad} | {len(claims) - n_good - n_bad} |")
    for study, rs in by_study.items():
        out += ["", f"## {study}", ""]
        claims = [r for r in rs if r["verdict"]]
        if claims:
            out += ["| key | source | ours | unit | verdict |", "|---|---|---|---|---|"]
            for r in claims:
                ours = "—" if r["value"] is None else f"{r['value']:.4g}"
                se = f" ± {r['mc_stderr']:.2g}" if r["mc_stderr"] else ""
                out.append(
                    f"| `{r['key']}` | {r['source_relation']} {r['source_value']:g} | {ours}{se} | {r['unit']} "
                    f"| {r['verdict']} |"
                )
            out.append("")
        families: dict[str, list[str]] = {}
        for r in rs:
            families.setdefault(_family(r["key"]), []).append(r["key"])
        out += ["| key family | keys | e.g. |", "|---|---|---|"]
        for fam, keys in families.items():
            out.append(f"| `{fam}` | {len(keys)} | {numbers[keys[0]].get('description', '')} |")
    return "\n".join(out) + "\n"


def main(argv: list[str] | None = None) -> int:  # pragma: no cover - command line
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 3 or args[0] not in ("csv", "docs"):
        print(__doc__.split("\n\n")[-1], file=sys.stderr)
        return 2
    with open(args[1], encoding="utf-8") as fh:
        numbers = json.load(fh)
    text = to_csv(numbers) if args[0] == "csv" else markdown(numbers, args[1])
    with open(args[2], "w", encoding="utf-8") as fh:
        fh.write(text)
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
