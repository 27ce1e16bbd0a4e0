"""Shared output of the benchmarks: one line per value, and the JSON report."""
from railradio.io import write_json


def emit(report: dict, out: str | None) -> None:
    for k, val in report.items():
        print(f"{k:40s} {val:.4g}" if isinstance(val, float) else f"{k:40s} {val}")
    if out:
        write_json(out, report)
