"""The benchmarks (`make bench`) run against the current library: smoke runs of the nr,
handover and chain benchmarks on a few bursts or crossings, their reports complete, their
ratios finite and the engines' outcomes equal to the plain loops' (the figures they measure
are the README's; these tests time nothing)."""

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
            "--filed-epochs",
            "1",
            "--repeat",
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
    # the engine of FILED_COMMIT beside this tree's, when the clone has its history
    have = subprocess.run(
        ["git", "-C", str(ROOT), "cat-file", "-e", _filed_commit() + "^{commit}"], capture_output=True
    )
    if have.returncode == 0:
        for key in ("filed_engine.ms_per_burst.filed", "filed_engine.ms_per_burst.now", "filed_engine.speedup"):
            assert math.isfinite(rep[key]) and rep[key] > 0, key
    else:
        assert not any(k.startswith("filed_engine.") for k in rep)
    shares = [rep[f"project_share_{k}"] for k in ("link", "synthesis_and_channel", "correlation")]
    assert sum(shares) == pytest.approx(1.0)


def _filed_commit() -> str:
    """FILED_COMMIT as bench_nr.py states it (read from its text: the benchmark is a script)."""
    text = (ROOT / "benchmarks" / "bench_nr.py").read_text(encoding="utf-8")
    return text.split('FILED_COMMIT = "', 1)[1].split('"', 1)[0]


@pytest.mark.parametrize(
    ("script", "args", "agree"),
    [
        ("bench_handover.py", ["--runs-vector", "4", "--runs-loop", "2"], {"outcomes_identical": True}),
        ("bench_chain.py", ["--runs", "4"], {"identical_outcomes": True}),
        ("bench_fusion.py", ["--n-vector", "2000", "--n-loop", "20"], {"max_abs_difference_m": 1e-6}),
        (
            "bench_tunnel.py",
            ["--order", "4", "--n-rays", "2000", "--n-direct", "2", "--n-table", "50"],
            {"max_abs_rssi_difference_db": 0.01},
        ),
    ],
)
def test_bench_engines_against_their_plain_baselines(tmp_path, script, args, agree):
    """The handover, chain, fusion and tunnel benchmarks run on a few crossings, trials or
    receivers: each engine agrees with its plain baseline (identical outcomes, or within the
    stated tolerance: m, dB), and each ratio is finite."""
    out = tmp_path / "bench.json"
    subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / script), *args, "--out", str(out)],
        cwd=ROOT,
        env=dict(os.environ, OPENBLAS_NUM_THREADS="1"),
        check=True,
        timeout=600,
    )
    rep = json.loads(out.read_text())
    for key, want in agree.items():
        assert rep[key] is True if want is True else 0 <= rep[key] <= want, (key, rep[key])
    ratios = [v for k, v in rep.items() if k.startswith("speedup")]
    assert ratios and all(math.isfinite(v) and v > 0 for v in ratios)
