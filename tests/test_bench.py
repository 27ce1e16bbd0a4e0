"""The nr benchmark (`make bench`) runs against the current library: a smoke run on one
burst, two-epoch shards, its report complete and its ratios finite (the figures it measures
are the README's; this test times nothing)."""

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_bench_nr_smoke(tmp_path):
    out = tmp_path / "nr_bench.json"
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    subprocess.run(
        [
            sys.executable,
            str(ROOT / "benchmarks" / "bench_nr.py"),
            "--epochs",
            "1",
            "--shard-epochs",
            "2",
            "--exact-epochs",
            "1",
            "--variant-epochs",
            "1",
            "--out",
            str(out),
        ],
        cwd=ROOT,
        env=env,
        check=True,
        timeout=600,
    )
    rep = json.loads(out.read_text())
    for key in (
        "project_ms_per_epoch",
        "naive_ms_per_epoch",
        "speedup",
        "malloc_speedup",
        "exact_path_ms.exact",
        "exact_path_ratio.search",
        "exact_spill_cost_ratio",
        "exact_path_ms.band_edges",
        "band_edges_vs_band",
        "burst_ms.reference.total",
        "burst_ms.engine.total",
        "engine_speedup",
        "engine_speedup_receivers",
        "variants.parts_ms",
        "variants.per_variant_ms",
        "variants.speedup",
    ):
        assert math.isfinite(rep[key]) and rep[key] > 0, key
    shares = [rep[f"project_share_{k}"] for k in ("link", "synthesis_and_channel", "correlation")]
    assert sum(shares) == pytest.approx(1.0)
