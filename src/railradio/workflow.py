"""Helpers for the Snakemake side: the jobs' environment and script set-up.

Kept free of Snakemake imports so the library stays importable without it.
"""

from __future__ import annotations

import logging
import platform
import signal
import sys
from pathlib import Path


def _cpu_flags(path: str = "/proc/cpuinfo") -> set[str]:
    try:
        with open(path, encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("flags"):
                    return set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return set()


def cpu_pins(machine: str | None = None, flags: set[str] | None = None) -> dict[str, str]:
    """Environment that makes NumPy's and OpenBLAS's arithmetic the same on every x86-64
    machine with AVX2 and FMA (x86-64-v3: every Intel core since Haswell, every AMD core
    since Zen), whatever else the CPU has.

    Both libraries pick code paths at run time by the CPU, and the paths round differently:

    * NumPy dispatches its loops (exp, log, sin, cos, …) to AVX-512 code where the CPU has
      it (``X86_V4`` and later groups); disabled here, every machine runs the AVX2 loops.
    * OpenBLAS picks its matrix kernels by the CPU (Haswell, SkylakeX, …), and kernels sum
      in different orders; pinned to the Haswell kernels (the ones a Zen core also gets).

    Empty on other machines (aarch64, x86-64 without AVX2): their arithmetic is their own,
    and reproduction there holds within the tolerance rule only (``config/README.md``).
    scipy.fft (SSE2 pocketfft, no run-time dispatch) and numba without ``fastmath`` (no
    reassociation, no fused multiply-add) need nothing: their results do not depend on
    the CPU (``tests/test_portability.py``).
    """
    machine = platform.machine() if machine is None else machine
    flags = _cpu_flags() if flags is None else flags
    if machine not in ("x86_64", "AMD64") or not {"avx2", "fma"} <= flags:
        return {}
    return {"NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR", "OPENBLAS_CORETYPE": "Haswell"}


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
    # the same arithmetic on every machine of the kind (cpu_pins)
    **cpu_pins(),
}
"""Environment of every workflow job (set by ``workflow/rules/common.smk`` before any job
starts: glibc, NumPy and OpenBLAS read these variables when a process starts)."""


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
