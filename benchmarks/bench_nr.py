"""Benchmark of the nr receiver: the project's decimated frequency-domain receiver against
the naive full-burst correlation at 245.76 MHz, on the same epochs, in one run.

Naive: the received burst synthesized at the full rate (all 600 subcarriers, D = 1) and, per
candidate cell, one FFT correlation over the whole burst (2^20 points) split into the 64
SS-block windows. Project: the shipped config's path (synthesis at F_s/D_s, the front end's
ideal filter to F_s/D, per-block windows on the F_s/D_c lag grid). Reports ms per epoch for
each, their ratio, and the project's time shares; then what each shortcut's exact
replacement costs per epoch (railradio.nr.study.fidelity, the same paths as the fidelity target;
and the fast path's own exact spill, nr.channel.exact_spill, in shard-like runs), so that the
choice of what to keep is measured; and the band's exact completion by its symbol edges
(railradio.nr.synthesis.band_edges: ``exact_path_ms.band_edges``, and ``band_edges_vs_band`` against
what the full band adds to the production's time); and one burst through the reference path
(railradio.nr.engine.simulate) against the burst engine the study runs (railradio.nr.engine:
``burst_ms.*``, ``engine_speedup``); the shard-like run of the study's code now against the
same run of the engine the study ran before the burst engine (commit ``FILED_COMMIT``, its own
tree and config, extracted with ``git archive``: ``filed_engine.*``); and the reproduction map's
amplitude variants from one synthesis of the links' unit parts against each variant's own
(``variants.*``).

    python benchmarks/bench_nr.py --out results/benchmarks/nr_bench.json
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import scipy.fft as sfft
import yaml
from _report import best_of, emit

from railradio.nr.channel.link import ShadowingMap, link_budget
from railradio.nr.engine.simulate import scenario_from_config
from railradio.nr.receiver.correlator import Correlator
from railradio.nr.receiver.frontend import project, upsample
from railradio.nr.synthesis.synthesizer import Synthesizer
from railradio.nr.waveform.numerology import Numerology
from railradio.nr.waveform.ssb import qpsk_pool, reference_waveform
from railradio.workflow import JOB_ENV

# A shard-like run in a fresh process: consecutive epochs of realization r0 from epoch 2 500
# (an acquisition epoch first, as a shard starts) through simulate_epochs (channel, synthesis,
# both receivers), as the nr_shard jobs run them; from a source tree (argv[4], or this one's
# when empty: FILED_COMMIT's flat nr package has simulate_epochs in railradio.nr.simulate) and
# with the taps' spill as configured or set (argv[3]).
_SHARD_RUN = """
import json, resource, sys, time, yaml
if sys.argv[4]:
    sys.path.insert(0, sys.argv[4])
try:
    from railradio.nr.engine.epochs import simulate_epochs
    from railradio.nr.engine.simulate import scenario_from_config
except ImportError:
    from railradio.nr.simulate import scenario_from_config, simulate_epochs
from railradio.rng import spawn_key
cfg = yaml.safe_load(open(sys.argv[1]))
if sys.argv[3] != "as_configured":
    cfg["nr"]["channel"]["exact_spill"] = sys.argv[3] == "exact_spill"
scn = scenario_from_config(cfg["nr"])
ep = list(range(2500, 2500 + int(sys.argv[2])))
simulate_epochs(scn, ep[:3], cfg["seed"], spawn_key("nr", 0))  # warm-up: kernels, caches
r0, t0 = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
simulate_epochs(scn, ep, cfg["seed"], spawn_key("nr", 0))
r1, t1 = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
print(json.dumps({"wall_s": t1 - t0, "user_s": r1.ru_utime - r0.ru_utime,
                  "sys_s": r1.ru_stime - r0.ru_stime, "n": len(ep)}))
"""


def shard_run(
    config: str, n_epochs: int, tunables: bool, exact_spill: bool | None = False, src: str = "", cwd: str | None = None
) -> dict:
    """Time ``n_epochs`` bursts in a fresh process with or without the jobs' malloc
    settings (glibc reads them at process start, hence the subprocess), the taps' spill
    wrapped (the shortcut, ``exact_spill`` false), exact (``nr.channel.exact_spill``) or as
    ``config`` sets it (None), the library from ``src`` (default: this tree's)."""
    env = {**os.environ, **JOB_ENV}
    if not tunables:
        del env["GLIBC_TUNABLES"]
    spill = "as_configured" if exact_spill is None else "exact_spill" if exact_spill else "wrapped"
    out = subprocess.run(
        [sys.executable, "-c", _SHARD_RUN, config, str(n_epochs), spill, src],
        env=env,
        check=True,
        capture_output=True,
        text=True,
        timeout=1800,
        cwd=cwd,
    ).stdout
    return json.loads(out.strip().splitlines()[-1])


FILED_COMMIT = "39e1c11168ca666fb688b15e0a5034fdfef6ae9e"
"""The last commit whose nr shards ran the engine before the burst engine (2026-12-05 00:06):
``railradio.nr.simulate.simulate_epochs`` (Synthesis with the exact spill and the band's edges,
the front end, the Estimator's cell search and both receivers, each correlating on its own),
on a paper-scale config whose nr bursts are the current one's (the same deployment, channel,
traffic and receivers; the differences since are comments and study keys outside the bursts)."""


def filed_engine(config: str, n_epochs: int, repeat: int = 2) -> dict:
    """The shard-like run (:func:`shard_run`, the jobs' environment, the spill as configured)
    of the code in this tree against the same run of :data:`FILED_COMMIT`'s tree (``src`` and
    ``config`` from ``git archive``), alternated, the smaller process CPU time (user + system)
    of ``repeat`` each: ``filed_engine.ms_per_burst.{filed,now}`` and their ratio
    ``filed_engine.speedup``. Empty (with a line saying why) when the commit is not in this
    clone's history."""
    root = subprocess.run(["git", "rev-parse", "--show-toplevel"], capture_output=True, text=True).stdout.strip()
    have = root and subprocess.run(["git", "-C", root, "cat-file", "-e", FILED_COMMIT + "^{commit}"]).returncode == 0
    if not have:
        print(f"filed_engine: commit {FILED_COMMIT[:7]} not in this clone's history, not measured")
        return {}
    with tempfile.TemporaryDirectory() as tmp:
        archive = subprocess.run(
            ["git", "-C", root, "archive", FILED_COMMIT, "src", "config"], capture_output=True, check=True
        ).stdout
        subprocess.run(["tar", "-x", "-C", tmp], input=archive, check=True)
        trees = {"filed": (f"{tmp}/src", f"{tmp}/config/config.yaml"), "now": (f"{root}/src", os.path.abspath(config))}
        best: dict[str, float] = {}
        for _ in range(repeat):
            for name, (src, cfg) in trees.items():
                run = shard_run(cfg, n_epochs, True, exact_spill=None, src=src, cwd=tmp)
                best[name] = min(best.get(name, np.inf), 1e3 * (run["user_s"] + run["sys_s"]) / run["n"])
    return {
        "filed_engine.commit": FILED_COMMIT,
        "filed_engine.bursts": n_epochs,
        "filed_engine.ms_per_burst.filed": best["filed"],
        "filed_engine.ms_per_burst.now": best["now"],
        "filed_engine.speedup": best["filed"] / best["now"],
    }


def naive_correlation(z: np.ndarray, s_min: int, cfg, n_id1: np.ndarray, n_id2: np.ndarray) -> np.ndarray:
    """Full-burst |r[m]| per candidate via one 2^20-point FFT each, split per block: [C, B, K]."""
    num = Numerology(1)
    n = 1 << 20
    zf = sfft.fft(z, n, workers=1)
    v = num.symbol_start(cfg.ssb_first) - num.symbol_start(s_min)
    out = np.empty((len(n_id1), len(v), cfg.lags_full), dtype=np.float32)
    for c, (a, b) in enumerate(zip(n_id1, n_id2, strict=True)):
        ref = reference_waveform(num, int(a), int(b), int(cfg.ssb_first[0]))
        r = np.abs(sfft.ifft(zf * np.conj(sfft.fft(ref, n, workers=1)), workers=1))
        out[c] = r[v[:, None] + np.arange(cfg.lags_full)[None, :]]
    return out


def burst_engine(config: str, n_epochs: int) -> dict:
    """One burst through the reference path (railradio.nr.engine.simulate: Synthesis with the
    band's edges and the front end, then the Estimator's cell search and both receivers,
    each correlating on its own) against the burst engine the study runs (railradio.nr.engine:
    SpectralSynthesis, the front end in one spectral pass onto the lag grid, and
    SharedEstimator, each correlation computed once), on the same consecutive paper-scale
    epochs of realization r0 (an acquisition epoch first, as a shard starts), alternated
    epoch by epoch; process time per epoch, split into the burst (synthesis, edges, front
    end) and the receivers."""
    from railradio.nr.engine import SharedEstimator, SpectralSynthesis
    from railradio.nr.engine.simulate import Estimator, Synthesis
    from railradio.rng import spawn_key

    with open(config, encoding="utf-8") as fh:
        cfg = yaml.safe_load(fh)
    scn = scenario_from_config(cfg["nr"])
    key = spawn_key("nr", 0)
    paths = {
        "reference": (Synthesis(scn, cfg["seed"], key), Estimator(scn)),
        "engine": (SpectralSynthesis(scn, cfg["seed"], key), SharedEstimator(scn, on_lag_grid=True)),
    }
    first = 2500
    cost = {f"{p}.{part}": 0.0 for p in paths for part in ("burst", "receivers")}
    for i, e in enumerate(range(first, first + n_epochs + 1)):
        for name, (syn, est) in paths.items():
            if i == 0:  # warm-up (untimed): the acquisition epoch, kernels, caches
                est.start(e)
            t0 = time.process_time()
            b = syn(e)
            t1 = time.process_time()
            est(e, b.z, b.s_min)
            t2 = time.process_time()
            if i:
                cost[f"{name}.burst"] += t1 - t0
                cost[f"{name}.receivers"] += t2 - t1
    out = {f"burst_ms.{k}": 1e3 * v / n_epochs for k, v in cost.items()}
    for p in paths:
        out[f"burst_ms.{p}.total"] = out[f"burst_ms.{p}.burst"] + out[f"burst_ms.{p}.receivers"]
    out["engine_speedup"] = out["burst_ms.reference.total"] / out["burst_ms.engine.total"]
    out["engine_speedup_receivers"] = out["burst_ms.reference.receivers"] / out["burst_ms.engine.receivers"]
    return out


def variant_bursts(config: str, n_epochs: int) -> dict:
    """The reproduction map's amplitude variants (every M_T of ``nr.map.rrh_elements`` × every
    data rule of ``nr.map.data``: 16 at the shipped config) from one synthesis of the links'
    unit parts (railradio.nr.engine.variants.VariantSynthesis) against each variant's own
    synthesis (railradio.nr.engine.SpectralSynthesis), on the same consecutive paper-scale
    epochs of r0, alternated; process time per epoch of the bursts on the lag grid (no
    receivers): the parts (once per epoch), each variant's weighing, edges and front end, and
    the direct synthesis per variant; ``variants.break_even`` is the variant count from
    which the parts pay."""
    import copy

    from railradio.nr.engine import SpectralSynthesis
    from railradio.nr.engine.variants import VariantSynthesis
    from railradio.rng import spawn_key

    with open(config, encoding="utf-8") as fh:
        cfg = yaml.safe_load(fh)
    nr = cfg["nr"]
    scns = []
    for m_t in nr["map"]["rrh_elements"]:
        for over in nr["map"]["data"].values():
            c = copy.deepcopy(nr)
            c["antenna"]["rrh_elements"] = m_t
            c["traffic"].update(over)
            scns.append(scenario_from_config(c))
    key = spawn_key("nr", 0)
    vs = VariantSynthesis(scns, cfg["seed"], key)
    own = [SpectralSynthesis(s, cfg["seed"], key) for s in scns]
    t_parts = t_each = t_direct = 0.0
    for i, e in enumerate(range(2500, 2500 + n_epochs + 1)):
        t0 = time.process_time()
        vs(e)
        t1 = time.process_time()
        for o in own:
            o(e)
        t2 = time.process_time()
        if i:  # the first epoch warms the kernels and caches up
            t_parts += t1 - t0
            t_direct += t2 - t1
    # the parts alone: the same epochs again, one variant (what a variant adds is the rest)
    one = VariantSynthesis(scns[:1], cfg["seed"], key)
    for i, e in enumerate(range(2500, 2500 + n_epochs + 1)):
        t0 = time.process_time()
        one(e)
        if i:
            t_each += time.process_time() - t0
    k = len(scns)
    per_variant = (t_parts - t_each) / (k - 1) / n_epochs
    shared = t_each / n_epochs - per_variant
    direct = t_direct / n_epochs / k
    return {
        "variants.n": k,
        "variants.parts_ms": 1e3 * shared,
        "variants.per_variant_ms": 1e3 * per_variant,
        "variants.direct_ms_per_variant": 1e3 * direct,
        "variants.speedup": t_direct / t_parts,
        "variants.break_even": shared / (direct - per_variant),
    }


def fft_backends(repeat: int = 30) -> dict:
    """The receiver's FFT batches (the correlator's 64 × 1232 blocks, the synthesizer's
    457 × 128 symbols; complex64, one thread) through scipy.fft, which the receiver uses,
    beside numpy.fft and, when it is installed, ducc0 (GPL-2.0-or-later, so not a
    dependency of this MIT project: ``pip install ducc0`` to see what it would gain).
    µs per batch, best of ``repeat``."""
    rng = np.random.default_rng(2)
    out = {}
    backends = {"scipy": lambda a: sfft.ifft(a, axis=-1, workers=1), "numpy": lambda a: np.fft.ifft(a, axis=-1)}
    try:
        import ducc0

        backends["ducc0"] = lambda a: ducc0.fft.c2c(a, axes=(a.ndim - 1,), forward=False, inorm=2, nthreads=1)
    except ImportError:
        pass
    for shape in ((64, 1232), (457, 128)):
        a = (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)).astype(np.complex64)
        for name, fn in backends.items():
            out[f"fft_{name}_{shape[0]}x{shape[1]}_us"] = 1e6 * best_of(lambda fn=fn, a=a: fn(a), repeat)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="config/config.yaml")
    ap.add_argument("--epochs", type=int, default=6)
    ap.add_argument(
        "--shard-epochs",
        type=int,
        default=100,
        help="bursts of the shard-like runs with and without the malloc settings",
    )
    ap.add_argument(
        "--exact-epochs", type=int, default=3, help="epochs of the fidelity paths (the exact reference costs ~6 s each)"
    )
    ap.add_argument("--variant-epochs", type=int, default=3, help="epochs of the map's variants from one synthesis")
    ap.add_argument("--filed-epochs", type=int, default=100, help="bursts of the runs against FILED_COMMIT's engine")
    ap.add_argument(
        "--repeat",
        type=int,
        default=2,
        help="runs of each process-level comparison (heap settings, spill, filed engine), the best kept",
    )
    ap.add_argument("--filed-only", action="store_true", help="only the run against FILED_COMMIT's engine")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    if args.filed_only:
        emit(filed_engine(args.config, args.filed_epochs, args.repeat), args.out)
        return
    with open(args.config, encoding="utf-8") as fh:
        scn = scenario_from_config(yaml.safe_load(fh)["nr"])
    dep = scn.deployment
    rng = np.random.default_rng(1)
    pool = qpsk_pool(rng, scn.pool_size)
    shadow = ShadowingMap(1, (0, 0, 1), dep, scn.radio)
    d_fe = scn.receiver.decimation
    d_s = scn.synthesis_decimation or d_fe
    d_c = scn.search_decimation or d_fe
    fast_syn = Synthesizer(
        dataclasses.replace(scn.receiver, decimation=d_s), scn.profile, pool, scn.n_sinusoids, scn.full_channel_range_m
    )
    fast_cor = Correlator(
        dataclasses.replace(scn.receiver, decimation=d_c), scn.detector, scn.pfa, template_decimation=d_fe
    )

    def front(z):  # the front end's samples on the correlator's lag grid
        return upsample(project(z, d_fe // d_s), d_fe // d_c)

    cfg1 = dataclasses.replace(scn.receiver, decimation=1)
    full_syn = Synthesizer(cfg1, scn.profile, pool, scn.n_sinusoids, scn.full_channel_range_m)
    t_traj = 250.0 + 0.1 * np.arange(args.epochs)  # consecutive epochs at cruise speed
    x, v, _ = scn.trajectory.state(t_traj)
    for xe, ve in zip(x, v, strict=True):  # shadowing fields are built once per RRH and shard
        link_budget(float(xe), float(ve), dep, scn.radio, scn.rrh_array, scn.train_array, shadow)
    # warm-up (untimed): load the compiled kernels, cache the cells' grids and spectra
    lb = link_budget(float(x[0]), float(v[0]), dep, scn.radio, scn.rrh_array, scn.train_array, shadow)
    cand = np.searchsorted(lb.rrh, dep.nearest(float(x[0]), scn.cell_search.n_neighbours))
    for syn, cor in ((fast_syn, fast_cor), (full_syn, None)):
        z, s_min = syn(lb.links, rng, t0_s=float(t_traj[0]))
        if cor is not None:
            cor.correlate(front(z), s_min, lb.links.n_id1[cand], lb.links.n_id2[cand])
    times = {"link": 0.0, "synthesis": 0.0, "correlation": 0.0, "naive_synthesis": 0.0, "naive_correlation": 0.0}
    for xe, ve, te in zip(x, v, t_traj, strict=True):
        t0 = time.perf_counter()
        lb = link_budget(float(xe), float(ve), dep, scn.radio, scn.rrh_array, scn.train_array, shadow)
        d2d = np.hypot(dep.x_m[lb.rrh] - xe, dep.offset_m)
        cand = dep.nearest(float(xe), scn.cell_search.n_neighbours)
        pos = np.searchsorted(lb.rrh, cand)
        t1 = time.perf_counter()
        draws = fast_syn.draws(lb.links, rng)
        z, s_min = fast_syn(lb.links, rng, t0_s=float(te), d2d_m=d2d, draws=draws)
        t2 = time.perf_counter()
        fast_cor.correlate(front(z), s_min, lb.links.n_id1[pos], lb.links.n_id2[pos])
        t3 = time.perf_counter()
        draws1 = full_syn.draws(lb.links, rng)
        z1, s1 = full_syn(lb.links, rng, t0_s=float(te), d2d_m=d2d, draws=draws1)
        t4 = time.perf_counter()
        naive_correlation(z1, s1, cfg1, lb.links.n_id1[pos], lb.links.n_id2[pos])
        t5 = time.perf_counter()
        for k, dt in zip(times, (t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4), strict=True):
            times[k] += dt
    n = len(t_traj)
    proj = (times["link"] + times["synthesis"] + times["correlation"]) / n
    naive = (times["link"] + times["naive_synthesis"] + times["naive_correlation"]) / n
    report = {
        "epochs": n,
        "project_ms_per_epoch": 1e3 * proj,
        "naive_ms_per_epoch": 1e3 * naive,
        "speedup": naive / proj,
        "project_share_link": times["link"] / n / proj,
        "project_share_synthesis_and_channel": times["synthesis"] / n / proj,
        "project_share_correlation": times["correlation"] / n / proj,
        "naive_correlation_ms_per_epoch": 1e3 * times["naive_correlation"] / n,
        "paper_scale_epochs": 3 * scn.trajectory.n_epochs,
    }
    # the jobs' heap settings (railradio.workflow.JOB_ENV) against glibc's defaults, same
    # bursts, each in a fresh process, alternated and best of --repeat, with the configured
    # (exact) spill; and the wrapped spill (nr.channel.exact_spill false) with the jobs'
    # settings, whose band edges take the tone-by-tone path
    runs = {"malloc_default": [], "malloc_tuned": [], "wrapped_spill": []}
    for _ in range(args.repeat):
        for name in runs:
            runs[name].append(
                shard_run(args.config, args.shard_epochs, name != "malloc_default", exact_spill=name != "wrapped_spill")
            )
    for name in runs:
        best = min(runs[name], key=lambda r: r["wall_s"])
        report[f"{name}_ms_per_burst"] = 1e3 * best["wall_s"] / best["n"]
        report[f"{name}_sys_share"] = best["sys_s"] / (best["user_s"] + best["sys_s"])
    report["malloc_speedup"] = report["malloc_default_ms_per_burst"] / report["malloc_tuned_ms_per_burst"]
    report["exact_spill_cost_ratio"] = report["malloc_tuned_ms_per_burst"] / report["wrapped_spill_ms_per_burst"]
    report.update(fft_backends())
    report.update(burst_engine(args.config, max(args.epochs, 2) * 5))
    report.update(filed_engine(args.config, args.filed_epochs, args.repeat))
    report.update(variant_bursts(args.config, args.variant_epochs))
    report.update(exact_costs(args.config, args.exact_epochs))
    emit(report, args.out)


def exact_costs(config: str, n_epochs: int) -> dict:
    """ms per epoch of every path of the fidelity target (railradio.nr.study.fidelity) on
    ``n_epochs`` epochs at cruise speed, and each against the production path's: what
    replacing a shortcut by its exact computation would cost."""
    from railradio.nr.study.fidelity import FidelityRun
    from railradio.nr.study.workflow import receiver_selection
    from railradio.nr.synthesis.band_edges import BandEdges
    from railradio.rng import spawn_key

    with open(config, encoding="utf-8") as fh:
        cfg = yaml.safe_load(fh)
    from railradio.config import load_schema, validate_config

    validate_config(cfg, load_schema("workflow/schemas/config.schema.yaml"))
    scn = scenario_from_config(cfg["nr"])
    run = FidelityRun(scn, cfg["seed"], spawn_key("nr", 0), receiver_selection(cfg["nr"]))
    # the band's exact completion (railradio.nr.synthesis.band_edges), against the full band it replaces
    edges = BandEdges(run.fast, run.pool_ref, scn.receiver.decimation)
    secs: dict[str, float] = {}
    for k, e in enumerate(range(2500, 2501 + n_epochs)):
        x = float(scn.trajectory.state(np.array([e * scn.trajectory.dt_s]))[0][0])
        cand = scn.deployment.nearest(x, scn.cell_search.n_neighbours).astype(np.int64)
        out = run.epoch(e, cand, int(cand[0]))
        ep = run._inputs(e, cand, int(cand[0]))
        c = ep.common
        t0 = time.perf_counter()
        edges(ep.links, c["draws"], c["t0_s"], c["d2d_m"], c["serving"])
        out["seconds"]["band_edges"] = time.perf_counter() - t0
        if k == 0:
            continue  # warm-up: compiled kernels, caches
        for v, t in out["seconds"].items():
            secs[v] = secs.get(v, 0.0) + t / n_epochs
    rep = {f"exact_path_ms.{v}": 1e3 * t for v, t in secs.items()}
    rep.update({f"exact_path_ratio.{v}": t / secs["production"] for v, t in secs.items()})
    rep["band_edges_vs_band"] = secs["band_edges"] / (secs["band"] - secs["production"])
    return rep


if __name__ == "__main__":
    main()
