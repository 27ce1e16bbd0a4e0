"""Shared fixtures. Every random draw uses an explicit generator (no global seeding).

The CI-scale pipeline (``config/ci.yaml``) runs once per test session, in a private copy of
the workflow (:func:`ci_run`); every test that needs its results shares that run. It starts
in the background as the session begins, the tests that need it are put last, and the others
run meanwhile. ``make test`` runs the suite on two pytest-xdist workers (``--dist
loadgroup``), which share the one pipeline run; the tests of a module with a module-scoped
fixture stay on one worker (their fixture is built once), as do the SLURM tests (one local
cluster).
"""

import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

if os.environ.get("PYTEST_XDIST_WORKER"):
    # before NumPy loads OpenBLAS: one BLAS thread a worker, as the jobs run
    # (railradio.workflow.JOB_ENV); a pool in each worker oversubscribes the cores
    for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).parent / "snakemake")
PIPELINE_TIMEOUT_S = 1800
"""Longest a CI-scale pipeline run may take (it takes ~5 min on 2 cores)."""
COMMAND_TIMEOUT_S = 300
"""Longest a dry run, lint or other short command may take."""


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


def copy_workflow(dest: Path) -> Path:
    """A private copy of the workflow (workflow/: Snakefile, rules, profiles; config, paper,
    library) in ``dest``. The library's ``__pycache__`` comes along, with the times of the
    sources kept (``copy2``): the bytecode and numba's compiled kernels stay valid in the copy
    (both check the source's time and size; numba also the CPU), so its jobs load the
    kernels the session has compiled instead of compiling them again (≈ 5 s of CPU a process
    for the nr kernels). A test that edits a module changes its time and size, which
    invalidates both."""
    for name in ("workflow", "config", "paper", "src"):
        src = ROOT / name
        if src.is_dir():
            shutil.copytree(src, dest / name, ignore=shutil.ignore_patterns("*.egg-info"))
        else:
            shutil.copy2(src, dest / name)
    return dest


def workflow_env(wd: Path, **extra: str) -> dict[str, str]:
    """The environment of a run in the copy ``wd``: its library first on the path."""
    return {**os.environ, "PYTHONPATH": str(wd / "src"), "MPLBACKEND": "Agg", **extra}


def smk_command(*args: str, ci: bool = True) -> list[str]:
    """The Snakemake command line with the default profile (and the CI config unless ``ci=False``)."""
    return [SNAKEMAKE, *args, "--workflow-profile", "workflow/profiles/default"] + (
        ["--configfile", "config/ci.yaml"] if ci else []
    )


def smk(
    wd: Path,
    *args: str,
    check: bool = True,
    ci: bool = True,
    timeout: float = PIPELINE_TIMEOUT_S,
    env: dict[str, str] | None = None,
) -> subprocess.CompletedProcess:
    """Run Snakemake in ``wd`` with the default profile (and the CI config unless ``ci=False``)."""
    cmd = smk_command(*args, ci=ci)
    run = subprocess.run(
        cmd, cwd=wd, env=env or workflow_env(wd), capture_output=True, text=True, check=False, timeout=timeout
    )
    if check and run.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} failed:\n{run.stdout[-3000:]}\n{run.stderr[-5000:]}")
    return run


CI_FIXTURE = "ci_run"


def _uses(item: pytest.Item, name: str) -> bool:
    return name in getattr(item, "fixturenames", ())


def _grouped_modules() -> frozenset[str]:
    """The test modules (paths relative to the repository) whose tests share a module-scoped
    fixture: those defining one, and every module of a directory whose conftest.py does."""
    out = set()
    for path in (ROOT / "tests").rglob("*.py"):
        if not re.search(r'^@pytest\.fixture\(scope="module"', path.read_text(encoding="utf-8"), re.MULTILINE):
            continue
        mods = path.parent.glob("test_*.py") if path.name == "conftest.py" else [path]
        out |= {str(m.relative_to(ROOT)) for m in mods}
    return frozenset(out)


GROUPED = _grouped_modules()


def _module_group(nodeid: str) -> str | None:
    """The test's group: ``slurm`` for the SLURM tests (one local cluster a session), its
    module for a module of :data:`GROUPED`, else none (the test is scheduled alone)."""
    module = nodeid.split("::")[0]
    if module.endswith("test_slurm.py"):
        return "slurm"
    return module if module in GROUPED else None


def _needs_ci(item: pytest.Item) -> bool:
    return _uses(item, CI_FIXTURE) or item.get_closest_marker("ci_run_last") is not None


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """The order: first the tests that need nothing of the CI-scale pipeline (they run while
    it does), then those that run something of their own before comparing it with the
    pipeline's (marked ``ci_run_last``: their runs, and the SLURM study's polling, overlap the
    pipeline's end; their group with them), last those that start from it (and their group;
    :func:`_module_group`). pytest-xdist's workers send this order to the scheduler
    (:func:`pytest_xdist_make_scheduler`), which keeps it."""
    groups = {id(item): _module_group(item.nodeid) for item in items}
    first = {groups[id(i)] for i in items if i.get_closest_marker("ci_run_last") and groups[id(i)]}
    late = {groups[id(i)] for i in items if _uses(i, CI_FIXTURE) and groups[id(i)]} - first

    def rank(item: pytest.Item) -> int:
        if item.get_closest_marker("ci_run_last") or groups[id(item)] in first:
            return 1
        return 2 if _uses(item, CI_FIXTURE) or groups[id(item)] in late else 0

    items.sort(key=rank)


def pytest_xdist_make_scheduler(config: pytest.Config, log):
    """With ``--dist loadgroup``: pytest-xdist's scope scheduler with our groups
    (:func:`_module_group`; a test without one is a unit of its own) and the collection's
    order kept. (pytest-xdist 3.8's own loadgroup reads groups from node ids it rewrites,
    which pytest 9 no longer lets it do: every test would be scheduled alone.)"""
    if config.getvalue("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class GroupScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return _module_group(nodeid) or nodeid

    config.option.loadscopereorder = False  # the collection's order: tests/conftest.py's ranks
    return GroupScheduling(config, log)


def _ci_root(tmp_path_factory) -> Path:
    """Where the session's CI-scale run lives: beside the workers' own temporary
    directories, so that every pytest-xdist worker finds the same run."""
    base = tmp_path_factory.getbasetemp()
    return (base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base) / "ci_pipeline"


_PIPELINE: list[subprocess.Popen] = []


def _start_ci_pipeline(root: Path) -> None:
    """Start the CI-scale run (every target of ``all``, -j2) in the background, unless a
    worker already has: its log goes to ``root/log.txt``, its exit status to ``root/rc``
    when it ends (a thread of this process waits for it)."""
    try:
        root.mkdir()
    except FileExistsError:
        return
    wd = copy_workflow(root / "wd")
    with open(root / "log.txt", "w", encoding="utf-8") as log:
        proc = subprocess.Popen(
            smk_command("all", "-j2"), cwd=wd, env=workflow_env(wd), stdout=log, stderr=subprocess.STDOUT
        )
    _PIPELINE.append(proc)

    def report() -> None:
        (root / "rc.part").write_text(str(proc.wait()))
        (root / "rc.part").rename(root / "rc")

    threading.Thread(target=report, daemon=True).start()


@pytest.fixture(scope="session", autouse=True)
def _ci_pipeline_started(request, tmp_path_factory):
    """The CI-scale run starts as the session does when a selected test needs it; the worker
    that started it waits for it at the end (another may still need it) and stops it when
    the session is interrupted."""
    if any(_needs_ci(item) for item in request.session.items):
        _start_ci_pipeline(_ci_root(tmp_path_factory))
    yield
    for proc in _PIPELINE:
        try:
            proc.wait(timeout=PIPELINE_TIMEOUT_S)
        except (KeyboardInterrupt, subprocess.TimeoutExpired):
            proc.send_signal(signal.SIGINT)
            proc.wait(timeout=60)
            raise


@pytest.fixture(scope="session")
def ci_run(tmp_path_factory) -> Path:
    """The CI-scale pipeline, run once per session at -j2 (every target of ``all``): its
    working directory, once the run has finished."""
    root = _ci_root(tmp_path_factory)
    _start_ci_pipeline(root)
    deadline = time.monotonic() + PIPELINE_TIMEOUT_S
    while not (root / "rc").exists():
        if time.monotonic() > deadline:
            raise AssertionError(f"the CI-scale run did not finish in {PIPELINE_TIMEOUT_S} s")
        time.sleep(1)
    if (root / "rc").read_text().strip() != "0":
        log = (root / "log.txt").read_text(errors="replace")
        raise AssertionError(f"the CI-scale run failed:\n{log[-8000:]}")
    return root / "wd"
