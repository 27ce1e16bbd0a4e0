"""Helpers for the Snakemake side: the jobs' environment and script set-up.

Kept free of Snakemake imports so the library stays importable without it.
"""

from __future__ import annotations

import logging
import signal
import sys
from pathlib import Path

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
    # 12 -> 6 shards). The current receiver (ducc0 FFTs in place into reused buffers)
    # allocates little: bench_nr's ``malloc_speedup`` was 0.89-1.00 in three runs on
    # 2026-11-22, no gain any more, kept as a guard for jobs with large temporaries.
    # Results do not depend on it.
    "GLIBC_TUNABLES": "glibc.malloc.mmap_threshold=268435456:glibc.malloc.trim_threshold=268435456",
}
"""Environment of every workflow job (set by ``workflow/rules/common.smk``; glibc reads
``GLIBC_TUNABLES`` at process start, so it is set before the jobs' processes start)."""


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
        sys.stderr = open(log_path, "a", encoding="utf-8")  # noqa: SIM115 - lives with the job
    else:
        handler = logging.StreamHandler()
    handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(message)s"))
    logger.handlers[:] = [handler]
    return logger
