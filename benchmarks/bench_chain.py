"""Benchmark of the chain study: one shared block context for every position input vs the
plain way, the handover engine re-run per input.

Both produce the same outcomes for the Gauss–Markov inputs (the handover engine with an
unreachable clip bound is the chain's untruncated process; checked in the same run); the
report is crossings × inputs per second for each and their ratio, plus the nr bootstrap's
throughput against a per-crossing Python loop drawing the same segments.

    python benchmarks/bench_chain.py --out results/benchmarks/chain_bench.json
"""

from __future__ import annotations

import argparse
import platform
from dataclasses import replace

import numpy as np
from _report import best_of, emit

from railradio.chain.nr_error import bootstrap, series_from_runs
from railradio.chain.sim import gm_label, simulate_block
from railradio.handover.engine import simulate_block as ho_simulate_block
from railradio.handover.params import Scenario


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=None, help="JSON report path")
    ap.add_argument("--runs", type=int, default=100, help="crossings per block")
    args = ap.parse_args()
    speed = 350.0
    sigmas = [0.0, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0]
    base = Scenario().with_weights(2, 0.5)
    base = replace(base, train=replace(base.train, gnss_bound_m=1000.0))

    t_shared = best_of(lambda: simulate_block(base, speed, 1, 0, args.runs, sigmas, 1.0, {}), 2)

    def plain():
        return {
            s: ho_simulate_block(
                replace(base, train=replace(base.train, gnss_sigma_m=s)),
                speed,
                1,
                0,
                args.runs,
                ("joint", "distance", "a3"),
            )
            for s in sigmas
        }

    t_plain = best_of(plain, 1)
    ours, ref = simulate_block(base, speed, 1, 0, args.runs, sigmas, 1.0, {}), plain()
    same = all(
        np.array_equal(ours[gm_label(s)][p]["success"], np.asarray(ref[s][p]["success"][1], dtype=float))
        for s in sigmas
        for p in ("joint", "distance", "a3")
    )

    # bootstrap: vectorized vs a per-crossing loop over the same draws
    n = 20_000
    t_epochs = np.arange(n) * 0.1
    import xarray as xr

    rng = np.random.default_rng(0)
    ds = xr.Dataset(
        {
            "along_err": (("filter", "epoch"), rng.standard_normal((1, n))),
            "t": ("epoch", t_epochs),
            "x_true": ("epoch", speed / 3.6 * t_epochs),
        },
        coords={"filter": ["ekf"]},
    )
    series = series_from_runs([ds], "ekf", speed, 50.0, 0.5)
    n_runs, k = 2000, 431
    t_boot = best_of(lambda: bootstrap(series, n_runs, k, 0.04, np.random.default_rng(1)), 3)

    def loop():
        g = np.random.default_rng(1)
        u, ph = g.integers(0, series.n_epochs, n_runs), g.random(n_runs)
        out = np.empty((n_runs, k))
        for b in range(n_runs):
            for j in range(k):
                out[b, j] = series.err_m[(u[b] + int(ph[b] + j * 0.4 + 1e-9)) % series.n_epochs]
        return out

    t_loop = best_of(loop, 1)
    report = {
        "machine": platform.processor() or platform.machine(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "shared_context_crossing_inputs_per_s": args.runs * len(sigmas) / t_shared,
        "handover_engine_per_input_crossing_inputs_per_s": args.runs * len(sigmas) / t_plain,
        "speedup_shared_over_per_input": t_plain / t_shared,
        "identical_outcomes": bool(same),
        "bootstrap_vectorized_samples_per_s": n_runs * k / t_boot,
        "bootstrap_loop_samples_per_s": n_runs * k / t_loop,
        "speedup_bootstrap_vectorized_over_loop": t_loop / t_boot,
    }
    emit(report, args.out)


if __name__ == "__main__":
    main()
