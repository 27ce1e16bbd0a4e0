"""Numbers that travel: the key numbers do not depend on the CPU they are computed on.

What can differ between machines of the kind (x86-64 with AVX2 and FMA), and how each is
handled (railradio.workflow.cpu_pins):

* numba compiles the nr kernels for the host CPU. Without ``fastmath`` the compiler may
  not reorder sums or fuse multiply-adds, so the host build and a build for a generic
  x86-64 (no AVX, no FMA) must give the same numbers: tested here on a CI-scale slice.
* NumPy's and OpenBLAS's run-time code paths are pinned by the jobs' environment (tested
  below: the pins are in JOB_ENV and in effect in a job's process, NumPy knows their names,
  and OpenBLAS's kernels really sum differently).
* scipy.fft's pocketfft is compiled for SSE2 only and has no run-time dispatch.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from railradio.arithmetic import beyond_v3, cpu_pins
from railradio.keynumbers import compare
from railradio.workflow import JOB_ENV

from .conftest import COMMAND_TIMEOUT_S, ROOT, copy_workflow, smk, workflow_env

NR_SLICE = ("results/nr/key_numbers.json", "results/nr/imm/key_numbers.json")


@pytest.mark.slow
@pytest.mark.ci_run_last
def test_generic_cpu_build_of_the_kernels_gives_the_same_nr_numbers(request, tmp_path):
    """The nr study at CI scale with numba compiling for a generic x86-64 CPU, at -j1,
    against the session's host build at -j2: the key numbers agree within the
    reproduction rule (and the per-shard estimates are identical)."""
    wd = copy_workflow(tmp_path)
    env = workflow_env(wd, NUMBA_CPU_NAME="generic")
    smk(wd, *NR_SLICE, "-j1", env=env)
    probe = subprocess.run(
        [sys.executable, "-c", "from numba.core import config; print(config.CPU_NAME, repr(config.CPU_FEATURES))"],
        env=env,
        capture_output=True,
        text=True,
        check=True,
        timeout=COMMAND_TIMEOUT_S,
    )
    assert probe.stdout.split()[:2] == ["generic", "''"], probe.stdout  # no host features
    ci_run = request.getfixturevalue("ci_run")
    n_keys = 0
    for frag in NR_SLICE:
        ours, host = (json.loads((d / frag).read_text()) for d in (wd, ci_run))
        n_keys += len(ours)
        msgs = compare(ours, host, mode="reproduce")
        assert msgs == [], "\n".join(msgs)
    assert n_keys > 40
    for shard in sorted((ci_run / "results/nr/estimates").rglob("*.nc")):
        with xr.open_dataset(shard) as a, xr.open_dataset(wd / shard.relative_to(ci_run)) as b:
            for name in a.data_vars:
                np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=f"{shard.name}: {name}")


def test_jobs_pin_numpy_and_openblas_code_paths_on_x86_64_v3():
    v3 = {"X86_V2": True, "X86_V3": True, "X86_V4": False}
    pins = cpu_pins("x86_64", v3, ["X86_V3", "X86_V4", "AVX512_ICL", "AVX512_SPR"])
    assert pins == {"NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR", "OPENBLAS_CORETYPE": "Haswell"}
    # NumPy before 2.4 names the AVX-512 features one by one
    assert beyond_v3(["AVX2", "FMA3", "AVX512F", "AVX512_SKX"]) == ["AVX512F", "AVX512_SKX"]
    assert cpu_pins("x86_64", {"X86_V2": True, "X86_V3": False}, ["X86_V3"]) == {}  # no Haswell kernels there
    assert cpu_pins("aarch64", v3, ["X86_V3"]) == {}
    assert all(JOB_ENV.get(k) == v for k, v in cpu_pins().items())


def test_the_pins_are_known_to_numpy_and_in_effect_in_a_job():
    """In a process with the jobs' environment, NumPy accepts every feature name it is
    asked to disable (an unknown name is only an ImportWarning: made an error here), runs
    no loop above AVX2, and both OpenBLAS libraries run the Haswell kernels."""
    if not cpu_pins():
        pytest.skip("not an x86-64-v3 machine: nothing is pinned")
    prog = (
        "import json; from railradio.arithmetic import in_effect, pins_hold; "
        "print(json.dumps([pins_hold(), in_effect()]))"
    )
    env = workflow_env(ROOT, **JOB_ENV)
    run = subprocess.run(
        [sys.executable, "-W", "error::ImportWarning", "-c", prog],
        env=env,
        capture_output=True,
        text=True,
        check=False,
        timeout=COMMAND_TIMEOUT_S,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    holds, eff = json.loads(run.stdout)
    assert holds and eff["numpy_simd"] == "X86_V3" and set(eff["openblas_core"].values()) == {"Haswell"}, eff


_BLAS_SUMS = """
import hashlib, numpy as np
rng = np.random.default_rng(0)
a = rng.standard_normal((96, 1232)).astype(np.float32); b = rng.standard_normal((1232, 18)).astype(np.float32)
x = rng.standard_normal((9, 9))
print(hashlib.sha256((a @ b).tobytes() + (x @ x.T).tobytes()).hexdigest())
"""


def _blas_digest(coretype: str) -> str:
    env = workflow_env(ROOT, OPENBLAS_CORETYPE=coretype, OPENBLAS_NUM_THREADS="1")
    return subprocess.run(
        [sys.executable, "-c", _BLAS_SUMS],
        env=env,
        capture_output=True,
        text=True,
        check=True,
        timeout=COMMAND_TIMEOUT_S,
    ).stdout.strip()


def test_openblas_kernels_sum_differently_so_the_pin_matters():
    """Why OPENBLAS_CORETYPE is pinned: another kernel family gives other float sums for
    the products the receiver and the trackers compute (Nehalem: SSE kernels, runnable on
    any x86-64)."""
    if not cpu_pins():
        pytest.skip("not an x86-64-v3 machine: nothing is pinned")
    assert _blas_digest("Haswell") == _blas_digest("Haswell")
    assert _blas_digest("Haswell") != _blas_digest("Nehalem")


def test_no_compiled_kernel_uses_fastmath():
    """fastmath lets the compiler reorder float sums by the host's vector width (the old
    TOA-refinement kernel gave other sums on AVX-512 than on AVX2)."""
    from numba.core.registry import CPUDispatcher

    import railradio.nr.receiver.kernels as receiver_kernels
    import railradio.nr.synthesis.kernels as synthesis_kernels

    found = [v for m in (receiver_kernels, synthesis_kernels) for v in vars(m).values() if isinstance(v, CPUDispatcher)]
    assert len(found) >= 16
    assert all(not d.targetoptions.get("fastmath") for d in found), [d.__name__ for d in found]
