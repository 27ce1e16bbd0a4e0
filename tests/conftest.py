"""Shared fixtures. Every random draw uses an explicit generator (no global seeding).

The CI-scale pipeline (``config/ci.yaml``) runs once per test session, in a private copy of
the workflow (:func:`ci_run`); every test that needs its results shares that run.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

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
    library) in ``dest``."""
    for name in ("workflow", "config", "paper", "src"):
        src = ROOT / name
        if src.is_dir():
            shutil.copytree(src, dest / name, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
        else:
            shutil.copy2(src, dest / name)
    return dest


def workflow_env(wd: Path, **extra: str) -> dict[str, str]:
    """The environment of a run in the copy ``wd``: its library first on the path."""
    return {**os.environ, "PYTHONPATH": str(wd / "src"), "MPLBACKEND": "Agg", **extra}


def smk(
    wd: Path,
    *args: str,
    check: bool = True,
    ci: bool = True,
    timeout: float = PIPELINE_TIMEOUT_S,
    env: dict[str, str] | None = None,
) -> subprocess.CompletedProcess:
    """Run Snakemake in ``wd`` with the default profile (and the CI config unless ``ci=False``)."""
    cmd = [SNAKEMAKE, *args, "--workflow-profile", "workflow/profiles/default"]
    if ci:
        cmd += ["--configfile", "config/ci.yaml"]
    run = subprocess.run(
        cmd, cwd=wd, env=env or workflow_env(wd), capture_output=True, text=True, check=False, timeout=timeout
    )
    if check and run.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} failed:\n{run.stdout[-3000:]}\n{run.stderr[-5000:]}")
    return run


@pytest.fixture(scope="session")
def ci_run(tmp_path_factory) -> Path:
    """The CI-scale pipeline, run once per session at -j2 (every target of ``all``)."""
    wd = copy_workflow(tmp_path_factory.mktemp("ci"))
    smk(wd, "all", "-j2")
    return wd
