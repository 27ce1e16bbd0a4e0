"""Shared fixtures. Every random draw uses an explicit generator (no global seeding)."""
import shutil
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


def copy_workflow(dest: Path) -> Path:
    """A private copy of the workflow (Snakefile, rules, config, paper, library) in ``dest``."""
    for name in ("Snakefile", "workflow", "config", "paper", "src"):
        src = ROOT / name
        if src.is_dir():
            shutil.copytree(src, dest / name, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
        else:
            shutil.copy2(src, dest / name)
    return dest
