"""Benchmark of the tunnel study's ray engines and of the tabulated channel.

Measured in the same run: rays per second of the image method (3-D rays evaluated) and
of the shooting-and-bouncing engine (2-D rays traced through the circular cross-section,
and their 3-D rays evaluated); the RSSI of receivers along the tunnel from the tabulated
slot-to-receiver channel against direct tracing of every slot-receiver pair (the same
rays, lifted at the exact offsets), with the largest difference between the two.

    python benchmarks/bench_tunnel.py --out results/benchmarks/tunnel_bench.json
"""

from __future__ import annotations

import argparse
import math
import platform
import time

import numpy as np
import yaml
from _report import best_of, emit

from railradio.tunnel.channel import offset_grid_m, received, slot_powers, tabulate
from railradio.tunnel.geometry import Cable, Tunnel
from railradio.tunnel.lifting import lift
from railradio.tunnel.materials import CONCRETE_900MHZ
from railradio.tunnel.rays import image_families, sbr_families, trace_2d
from railradio.tunnel.study import local_mean_window


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=None)
    ap.add_argument("--config", default="config/config.yaml", help="its tunnel section's local-mean window")
    ap.add_argument("--order", type=int, default=16, help="reflection order (paper scale: 16)")
    ap.add_argument("--n-rays", type=int, default=100_000)
    ap.add_argument("--n-direct", type=int, default=20, help="receivers traced directly")
    ap.add_argument("--n-table", type=int, default=5000, help="receivers from the table")
    args = ap.parse_args()

    rect, circ, cab = Tunnel(shape="rect"), Tunnel(shape="circle"), Cable()
    lam = cab.wavelength_m
    offs = np.linspace(0.0, 1000.0, 200)

    fam_img = image_families(rect, args.order)
    t_img = best_of(lambda: lift(fam_img, offs, lam, CONCRETE_900MHZ, "paraxial"), 3)
    phi = (np.arange(args.n_rays) + 0.5) * 2 * math.pi / args.n_rays
    t_trace = best_of(lambda: trace_2d(circ, phi, args.order, 0.05), 3)
    t_sbr = best_of(lambda: sbr_families(circ, args.n_rays, args.order, 0.05), 2)
    fam_sbr = sbr_families(circ, args.n_rays, args.order, 0.05)
    t_sbr_lift = best_of(lambda: lift(fam_sbr, offs, lam, CONCRETE_900MHZ, "vector"), 3)

    # tabulated channel vs direct tracing of every slot-receiver pair
    grid = offset_grid_m(0.04, 1000.0, rect.slot_spacing_m)
    with open(args.config, encoding="utf-8") as fh:
        window_m = local_mean_window(yaml.safe_load(fh)["tunnel"])
    t0 = time.perf_counter()
    table = tabulate(
        fam_img, rect, cab, grid, eps=CONCRETE_900MHZ, polarization="paraxial", local_mean_window_m=window_m
    )
    t_build = time.perf_counter() - t0
    rng = np.random.default_rng(1)
    x_tab = np.round(rng.uniform(1000, 4000, args.n_table) / 0.04) * 0.04
    t_tab = best_of(lambda: received(table, rect, cab, x_tab), 2)
    xs, pc_dbm, tc = slot_powers(rect, cab)
    amp_c = 10 ** ((pc_dbm - 30) / 20) * np.exp(-2j * math.pi * cab.frequency_hz * tc)
    eirp = 10 ** (cab.slot_eirp_offset_db(rect.slot_spacing_m) / 20)
    x_dir = x_tab[: args.n_direct]

    def direct():
        out = np.empty(x_dir.size)
        for i, x in enumerate(x_dir):
            near = np.abs(x - xs) <= 1000.0
            a = lift(fam_img, x - xs[near], lam, CONCRETE_900MHZ, "paraxial").amplitude.sum(axis=0)
            out[i] = 10 * np.log10(np.abs(np.sum(amp_c[near] * eirp * a)) ** 2) + 30
        return out

    t_dir = best_of(direct, 1)
    diff = np.max(np.abs(direct() - received(table, rect, cab, x_dir).rssi_coherent_dbm))
    per_dir, per_tab = t_dir / x_dir.size, t_tab / x_tab.size
    report = {
        "machine": platform.processor() or platform.machine(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "reflection_order": args.order,
        "image_rays_per_slot": len(fam_img),
        "image_3d_rays_per_s": len(fam_img) * offs.size / t_img,
        "sbr_2d_rays_traced_per_s": args.n_rays / t_trace,
        "sbr_2d_ray_segments_per_s": args.n_rays * (args.order + 1) / t_trace,
        "sbr_families_found_per_slot": len(fam_sbr),
        "sbr_engine_s": t_sbr,
        "sbr_3d_rays_per_s": len(fam_sbr) * offs.size / t_sbr_lift,
        "table_build_s": t_build,
        "direct_tracing_s_per_receiver": per_dir,
        "tabulated_s_per_receiver": per_tab,
        "speedup_tabulated_over_direct": per_dir / per_tab,
        "break_even_receivers": t_build / max(per_dir - per_tab, 1e-12),
        "max_abs_rssi_difference_db": float(diff),
    }
    emit(report, args.out)


if __name__ == "__main__":
    main()
