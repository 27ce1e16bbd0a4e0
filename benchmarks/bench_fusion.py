"""Benchmark of the fusion study's estimator: vectorized closed form vs per-trial root finding.

Both solve the same TDOA ∩ track problem on the same random range differences, in the same
run; the report is trials per second for each and their ratio, plus the throughput of the
whole Monte Carlo driver (TDOA, AOA, two fusions per trial), and the same comparison for
the sensitivity study's TDOA on a circular-arc track (safeguarded Newton vs Brent).

    python benchmarks/bench_fusion.py --out results/benchmarks/fusion_bench.json
"""

from __future__ import annotations

import argparse
import platform

import numpy as np
from _report import best_of, emit
from scipy.optimize import brentq

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.fusion import CellGeometry, PointParams, simulate_point, tdoa_on_track, tdoa_on_track_rootfind
from railradio.fusion.arc import ArcGeometry, tdoa_on_arc


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=None, help="JSON report path")
    ap.add_argument("--n-vector", type=int, default=2_000_000)
    ap.add_argument("--n-loop", type=int, default=2_000)
    args = ap.parse_args()

    geom = CellGeometry(1500.0)
    rng = np.random.default_rng(1)
    x = rng.uniform(*geom.train_interval_m, size=args.n_vector)
    delta = geom.range_difference_m(x) + SPEED_OF_LIGHT_M_S * 1e-7 * rng.standard_normal(args.n_vector)

    t_vec = best_of(lambda: tdoa_on_track(delta, geom), 5)
    loop_in = delta[: args.n_loop]
    t_loop = best_of(lambda: [tdoa_on_track_rootfind(float(d), geom) for d in loop_in], 2)
    # same answers on the shared trials
    ref = np.array([tdoa_on_track_rootfind(float(d), geom) for d in loop_in])
    max_diff = float(np.max(np.abs(tdoa_on_track(loop_in, geom)[0] - ref)))

    point = PointParams(1500.0, 1e-7, 0.01, n_positions=200, n_trials=10_000)
    t_mc = best_of(lambda: simulate_point(point, 1, (2, 0)), 2)

    # sensitivity: TDOA on a 4 km arc, vectorized safeguarded Newton vs per-trial
    # Brent root finding on the same branch and the same range differences
    arc = ArcGeometry(1500.0, 4000.0)
    s_true = rng.uniform(*arc.train_interval_m, size=args.n_vector // 4)
    delta_arc = arc.range_difference_m(s_true) + SPEED_OF_LIGHT_M_S * 1e-7 * rng.standard_normal(s_true.size)
    t_arc_vec = best_of(lambda: tdoa_on_arc(delta_arc, arc), 3)
    s_a, s_b = arc.tdoa_branch_m

    def arc_brent(dl: float) -> float:
        return brentq(lambda s: float(arc.range_difference_m(s)) - dl, s_a, s_b, xtol=1e-9, rtol=1e-14)

    arc_in = delta_arc[: args.n_loop]
    t_arc_loop = best_of(lambda: [arc_brent(float(dl)) for dl in arc_in], 2)
    arc_ref = np.array([arc_brent(float(dl)) for dl in arc_in])
    arc_max_diff = float(np.max(np.abs(tdoa_on_arc(arc_in, arc)[0] - arc_ref)))

    vec_rate = args.n_vector / t_vec
    loop_rate = args.n_loop / t_loop
    report = {
        "machine": platform.processor() or platform.machine(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "closed_form_vectorized_trials_per_s": vec_rate,
        "rootfind_per_trial_trials_per_s": loop_rate,
        "speedup_closed_form_over_rootfind": vec_rate / loop_rate,
        "max_abs_difference_m": max_diff,
        "monte_carlo_driver_trials_per_s": point.n_positions * point.n_trials / t_mc,
        "paper_scale_point_s": 1000 * 10_000 / (point.n_positions * point.n_trials / t_mc),
        "arc_newton_vectorized_trials_per_s": delta_arc.size / t_arc_vec,
        "arc_brent_per_trial_trials_per_s": args.n_loop / t_arc_loop,
        "speedup_arc_newton_over_brent": (delta_arc.size / t_arc_vec) / (args.n_loop / t_arc_loop),
        "arc_max_abs_difference_m": arc_max_diff,
    }
    emit(report, args.out)


if __name__ == "__main__":
    main()
