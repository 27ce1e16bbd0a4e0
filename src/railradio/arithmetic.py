"""The CPU-dependent code paths of the numeric libraries: what the jobs pin, and what is in
effect in a process.

NumPy and OpenBLAS choose code paths at run time by the CPU, and the paths round
differently:

* NumPy dispatches its loops (exp, log, sin, cos, …) to AVX-512 code where the CPU has it
  (the dispatch targets beyond ``X86_V3``); pinned off, every machine runs the AVX2 loops;
* OpenBLAS picks its matrix kernels by the CPU (Haswell, SkylakeX, Zen, …), and kernels sum
  in different orders; pinned to the Haswell kernels (the ones a Zen core also gets).

The pins apply on x86-64 machines on which NumPy finds its ``X86_V3`` group (AVX2, FMA, F16C,
BMI1/2, LZCNT, MOVBE: Intel since Haswell, AMD since Zen). Elsewhere (aarch64, an older
x86-64, a virtual CPU that masks one of those features) nothing is pinned, and reproduction
holds within the tolerance rule only (``config/README.md``). scipy.fft (pocketfft built for
SSE2, no run-time dispatch) and numba without ``fastmath`` (no reassociation, no fused
multiply-add) need nothing: their results do not depend on the CPU
(``tests/test_portability.py``).
"""

from __future__ import annotations

import ctypes
import glob
import os
import platform
from pathlib import Path

PIN_KEYS = ("NPY_DISABLE_CPU_FEATURES", "OPENBLAS_CORETYPE")
OPENBLAS_CORE = "Haswell"


def _numpy_cpu() -> tuple[dict[str, bool], list[str]]:
    """NumPy's CPU features (as enabled in this process) and its dispatch targets."""
    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__

    return dict(__cpu_features__), list(__cpu_dispatch__)


def beyond_v3(dispatch: list[str]) -> list[str]:
    """NumPy's dispatch targets above the AVX2 level (``X86_V4``, ``AVX512_*``; in NumPy
    before 2.4 the AVX-512 features one by one)."""
    return [t for t in dispatch if t == "X86_V4" or "AVX512" in t]


def cpu_pins(
    machine: str | None = None, features: dict[str, bool] | None = None, dispatch: list[str] | None = None
) -> dict[str, str]:
    """The environment that pins NumPy's and OpenBLAS's code paths on this machine (empty
    where nothing is pinned); the arguments default to this machine's."""
    machine = platform.machine() if machine is None else machine
    if features is None or dispatch is None:
        found, targets = _numpy_cpu()
        features = found if features is None else features
        dispatch = targets if dispatch is None else dispatch
    if machine not in ("x86_64", "AMD64") or not features.get("X86_V3", False):
        return {}
    return {"NPY_DISABLE_CPU_FEATURES": " ".join(beyond_v3(dispatch)), "OPENBLAS_CORETYPE": OPENBLAS_CORE}


def _openblas_cores() -> dict[str, str]:
    """The kernel family each bundled OpenBLAS (NumPy's, SciPy's) runs with in this process."""
    import numpy
    import scipy

    out = {}
    for pkg, syms in (
        (numpy, ("scipy_openblas_get_corename64_", "openblas_get_corename64_")),
        (scipy, ("scipy_openblas_get_corename", "openblas_get_corename")),
    ):
        libs = glob.glob(str(Path(pkg.__file__).parent.parent / f"{pkg.__name__}.libs" / "*openblas*"))
        for path in libs:
            lib = ctypes.CDLL(path)
            for sym in syms:
                fn = getattr(lib, sym, None)
                if fn is not None:
                    fn.restype = ctypes.c_char_p
                    out[pkg.__name__] = fn().decode()
                    break
    return out


def in_effect() -> dict[str, object]:
    """What this process runs: NumPy's highest enabled dispatch group and the OpenBLAS
    kernels (recorded in every output's provenance)."""
    features, _ = _numpy_cpu()
    groups = [g for g in ("X86_V2", "X86_V3", "X86_V4") if features.get(g)]
    return {
        "machine": platform.machine(),
        "numpy_simd": groups[-1] if groups else "baseline",
        "openblas_core": _openblas_cores(),
        "pinned": all(k in os.environ for k in PIN_KEYS),
    }


def pins_hold() -> bool:
    """Whether the pins this machine calls for are in effect in this process."""
    want = cpu_pins(features=None)
    if not want:
        return True
    eff = in_effect()
    return eff["numpy_simd"] == "X86_V3" and all(
        c.lower() == OPENBLAS_CORE.lower() for c in eff["openblas_core"].values()
    )
