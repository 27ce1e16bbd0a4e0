"""Helpers for the Snakemake side: the jobs' environment and script set-up.

Kept free of Snakemake imports so the library stays importable without it.
"""

from __future__ import annotations

import logging
import signal
import sys
from pathlib import Path

from railradio.arithmetic import cpu_pins, in_effect, pins_hold

JOB_ENV = {
    # one BLAS/OpenMP thread per job: Snakemake runs jobs in parallel (-j), and a BLAS
    # thread pool per job oversubscribes the cores (measured: 137 vs 83 ms CPU per nr epoch)
    "OPENBLAS_NUM_THREADS": "1",
    "OMP_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    # keep freed memory in the heap instead of handing it back to the kernel: jobs that
    # allocate and free multi-megabyte arrays thousands of times otherwise spend their
    # time in page faults under glibc's adaptive mmap/trim thresholds. Measured on the nr
    # study from nothing with the receiver of 2a1ef81, whose correlation allocated 4 MB
    # temporaries per burst: system time 196 -> 17 s, wall 9 min 28 s -> 6 min 40 s (with
    # 12 -> 6 shards). The current receiver allocates little (bench_nr's
    # ``malloc_speedup`` ≈ 1); kept as a guard for jobs with large temporaries.
    # Results do not depend on it.
    "GLIBC_TUNABLES": "glibc.malloc.mmap_threshold=268435456:glibc.malloc.trim_threshold=268435456",
    # the same arithmetic on every machine of the kind (railradio.arithmetic)
    **cpu_pins(),
}
"""Environment of every workflow job (set by ``workflow/rules/common.smk`` before any job
starts: glibc, NumPy and OpenBLAS read these variables when a process starts). The CPU
pins override the environment (results depend on them); ``RAILRADIO_CPU_PINS=0`` leaves
them out."""


def _raise_on_sigterm(signum, frame):  # pragma: no cover - signal path
    raise SystemExit(128 + signum)


def setup_script(log_path: str | None) -> logging.Logger:
    """Prepare a workflow script: log to the rule's log file; SIGTERM cleans up like Ctrl-C.

    Turning SIGTERM into ``SystemExit`` lets :func:`railradio.io.atomic_path` remove its
    temporary file when Snakemake (or SLURM) terminates a job.
    """
    signal.signal(signal.SIGTERM, _raise_on_sigterm)
    logger = logging.getLogger("railradio")
    logger.setLevel(logging.INFO)
    handler: logging.Handler
    if log_path:
        Path(log_path).parent.mkdir(parents=True, exist_ok=True)
        handler = logging.FileHandler(log_path, mode="w", encoding="utf-8")
        sys.stderr = open(log_path, "a", encoding="utf-8")
    else:
        handler = logging.StreamHandler()
    handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(message)s"))
    logger.handlers[:] = [handler]
    logger.info("arithmetic: %s", in_effect())
    if not pins_hold():
        logger.warning(
            "NumPy's or OpenBLAS's CPU code paths are not pinned in this job (%s): its "
            "numbers may differ from another machine's beyond rounding",
            in_effect(),
        )
    return logger
