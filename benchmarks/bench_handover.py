"""Benchmark of the handover study: the vectorized engine vs the plain per-step loop.

Both simulate the same crossings (identical random draws) with all three policies, in the
same run; the report is node handovers per second for each, their ratio, and whether the
outcomes agree on the crossings both simulated.

    python benchmarks/bench_handover.py --out results/benchmarks/handover_bench.json
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np
from _report import emit

from railradio.handover.model import build_context, draw_block
from railradio.handover.params import Scenario
from railradio.handover.policies import make_policy, run_policy
from railradio.handover.reference import simulate_reference
from railradio.handover.train import kinematics

POLICIES = ("joint", "a3", "distance")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=None, help="JSON report path")
    ap.add_argument("--speed", type=float, default=350.0)
    ap.add_argument("--runs-vector", type=int, default=250)
    ap.add_argument("--runs-loop", type=int, default=8)
    args = ap.parse_args()

    scn = Scenario().with_weights(3, 0.5)
    kin = kinematics(scn, args.speed)
    n_nodes = scn.train.n_nodes
    draws = draw_block(1, args.speed, 0, args.runs_vector, kin, n_nodes)

    def vectorized(d):
        ctx = build_context(scn, kin, d)
        return {p: run_policy(make_policy(p), ctx) for p in POLICIES}

    vectorized(draw_block(1, args.speed, 1, 4, kin, n_nodes))  # warm-up
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        vectorized(draws)
        times.append(time.perf_counter() - t0)
    t_vec = min(times)

    # the loop on a block of its own (the fast fading's draws are keyed by the block's shape,
    # so a slice of the large block is not a block), the engine's outcomes on it compared
    sub = draw_block(1, args.speed, 0, args.runs_loop, kin, n_nodes)
    t0 = time.perf_counter()
    ref = simulate_reference(scn, kin, sub, POLICIES)
    t_loop = time.perf_counter() - t0
    vec_sub = vectorized(sub)
    agree = all(
        np.allclose(vec_sub[p][k][1].astype(float), ref[p][k].astype(float), rtol=1e-9, atol=1e-9, equal_nan=True)
        for p in POLICIES
        for k in ("command_x_m", "success", "attempts", "pingpong", "delay_s")
    )

    vec_rate = args.runs_vector * n_nodes / t_vec
    loop_rate = args.runs_loop * n_nodes / t_loop
    report = {
        "machine": platform.processor() or platform.machine(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "speed_kmh": args.speed,
        "samples_per_crossing": kin.n_samples,
        "vectorized_handovers_per_s": vec_rate,
        "per_step_loop_handovers_per_s": loop_rate,
        "speedup_vectorized_over_loop": vec_rate / loop_rate,
        "outcomes_identical": agree,
        "policies_per_handover": len(POLICIES),
    }
    emit(report, args.out)


if __name__ == "__main__":
    main()
