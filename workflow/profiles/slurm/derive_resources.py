"""Per-rule SLURM resources of this profile, derived from measured jobs.

The measurement table ``measured.tsv`` (beside this file) holds, per rule, the largest
wall time and peak resident memory of its jobs in the last paper-scale run:

Snakemake's benchmark files ``results/benchmarks/**/*.tsv`` (columns ``s`` and ``max_rss``):
every rule that runs a job has a ``benchmark:`` directive, and each file is attributed to its
rule by the rule's benchmark pattern and wildcard constraints.

A rule not yet measured may carry a hand-written row with source ``estimate`` (a like
rule's values) until its first paper-scale run.

From the table, with a stated margin (the measuring machine was a loaded 2-core box, so
wall times are already pessimistic for a dedicated cluster core):

* ``mem_mb``  = max(1000, 2 x peak RSS rounded up to 500 MB);
* ``runtime`` = max(5, ceil(3 x wall / 60 s)) minutes;

both multiplied by ``attempt`` in the profile, so a job killed for time or memory is
retried once (``retries: 1``) with twice the limit.

Usage (from the repository root)::

    python workflow/profiles/slurm/derive_resources.py measure
    python workflow/profiles/slurm/derive_resources.py print     # the set-resources block

``tests/test_scale.py`` checks that the profile's set-resources equal ``derive()`` of the
committed table and that every rule that runs a job is covered.
"""

from __future__ import annotations

import argparse
import ast
import csv
import math
import re
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
TABLE = HERE / "measured.tsv"
COLUMNS = ("rule", "jobs", "wall_s_max", "max_rss_mb_max", "source")

MEM_FACTOR, MEM_STEP_MB, MEM_FLOOR_MB = 2.0, 500, 1000
TIME_FACTOR, TIME_FLOOR_MIN = 3.0, 5


def rules_in_workflow(root: Path = ROOT) -> dict[str, str]:
    """Rule name -> its text block, for every rule in ``workflow/rules/*.smk``."""
    blocks = {}
    for smk in sorted((root / "workflow/rules").glob("*.smk")):
        parts = re.split(r"^rule (\w+):\s*$", smk.read_text(), flags=re.M)
        for name, body in zip(parts[1::2], parts[2::2], strict=True):
            blocks[name] = body.split("\n\n\n")[0]
    return blocks


def _benchmark_regex(body: str) -> re.Pattern | None:
    m = re.search(r"^\s+benchmark:\s*\n\s+\"([^\"]+)\"", body, flags=re.M)
    if m is None:
        return None
    constraints = {}
    c = re.search(r"^\s+wildcard_constraints:\s*\n((?:\s{8}\w+=.*\n)+)", body, flags=re.M)
    if c:
        for line in c.group(1).strip().splitlines():
            key, val = line.strip().rstrip(",").split("=", 1)
            try:  # literal constraints only (they tell apart rules sharing a pattern)
                constraints[key] = ast.literal_eval(val)
            except ValueError:
                pass
    pattern, pos = "", 0
    for w in re.finditer(r"\{(\w+)\}", m.group(1)):
        pattern += re.escape(m.group(1)[pos : w.start()])
        pattern += f"(?P<{w.group(1)}>{constraints.get(w.group(1), '.+')})"
        pos = w.end()
    return re.compile(pattern + re.escape(m.group(1)[pos:]) + "$")


def measure(root: Path = ROOT) -> list[dict]:
    """The measurement table from the benchmark files."""
    regexes = {r: rx for r, body in rules_in_workflow(root).items() if (rx := _benchmark_regex(body))}
    per_rule: dict[str, list[tuple[float, float]]] = {}
    source: dict[str, str] = {}
    for tsv in sorted((root / "results/benchmarks").rglob("*.tsv")):
        rel = tsv.relative_to(root).as_posix()
        owners = [r for r, rx in regexes.items() if rx.match(rel)]
        if len(owners) != 1:
            raise ValueError(f"benchmark file {rel} matches rules {owners}")
        for row in csv.DictReader(tsv.open(), delimiter="\t"):
            per_rule.setdefault(owners[0], []).append((float(row["s"]), float(row["max_rss"])))
            source[owners[0]] = "benchmark"
    return [
        {
            "rule": r,
            "jobs": len(v),
            "wall_s_max": round(max(x[0] for x in v), 1),
            "max_rss_mb_max": round(max(x[1] for x in v), 1),
            "source": source[r],
        }
        for r, v in sorted(per_rule.items())
    ]


def read_table(path: Path = TABLE) -> list[dict]:
    with path.open() as fh:
        rows = list(csv.DictReader((ln for ln in fh if not ln.startswith("#")), delimiter="\t"))
    return [
        {
            **r,
            "jobs": int(r["jobs"]),
            "wall_s_max": float(r["wall_s_max"]),
            "max_rss_mb_max": float(r["max_rss_mb_max"]),
        }
        for r in rows
    ]


def write_table(rows: list[dict], path: Path = TABLE) -> None:
    with path.open("w") as fh:
        fh.write("# Largest wall time [s] and peak RSS [MB] per rule, paper-scale run; see derive_resources.py\n")
        w = csv.DictWriter(fh, COLUMNS, delimiter="\t", lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def derive(rows: list[dict]) -> dict[str, dict[str, int]]:
    """Rule -> {mem_mb, runtime} (attempt 1) by the stated margins."""
    out = {}
    for r in rows:
        mem = max(MEM_FLOOR_MB, math.ceil(MEM_FACTOR * r["max_rss_mb_max"] / MEM_STEP_MB) * MEM_STEP_MB)
        runtime = max(TIME_FLOOR_MIN, math.ceil(TIME_FACTOR * r["wall_s_max"] / 60.0))
        out[r["rule"]] = {"mem_mb": mem, "runtime": runtime}
    return out


def set_resources_yaml(res: dict[str, dict[str, int]]) -> str:
    lines = ["set-resources:"]
    for rule, v in res.items():
        lines += [f"  {rule}:", f'    mem_mb: "{v["mem_mb"]} * attempt"', f'    runtime: "{v["runtime"]} * attempt"']
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("command", choices=("measure", "print"))
    a = ap.parse_args(argv)
    if a.command == "measure":
        # rows measured now replace the table's; rules not measured now keep their row
        # (a rule added by hand before its first measurement: source 'estimate'); rules
        # gone from the workflow are dropped
        rows = {r["rule"]: r for r in (read_table() if TABLE.exists() else [])}
        rows.update({r["rule"]: r for r in measure(ROOT)})
        live = rules_in_workflow(ROOT)
        write_table([rows[r] for r in sorted(rows) if r in live])
    print(set_resources_yaml(derive(read_table())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
