"""Shared output of the benchmarks: one line per value, and the JSON report."""

import time

from railradio.io import write_json


def best_of(fn, repeat: int) -> float:
    """Smallest wall time [s] of ``repeat`` calls of ``fn``."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def emit(report: dict, out: str | None) -> None:
    for k, val in report.items():
        print(f"{k:40s} {val:.4g}" if isinstance(val, float) else f"{k:40s} {val}")
    if out:
        write_json(out, report)
