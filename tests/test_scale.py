"""Scale-out: the SLURM profile covers every rule with measured resources, and results do not
depend on how the work is split into jobs (shards, batches, chunks, realization subsets).

Each sharding test compares the one-piece computation with several splits, exactly
(``assert_equal``/``array_equal``, not a tolerance), and has a control showing that the
compared outputs are random draws (another key gives other values), so equality means
the same draws and not a vacuous comparison.
"""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

from railradio.config import deep_merge, load_schema, validate_config

from .conftest import COMMAND_TIMEOUT_S, PIPELINE_TIMEOUT_S, ROOT
from .conftest import copy_workflow as _copy_workflow

PROFILE = ROOT / "workflow/profiles/slurm"
SNAKEMAKE = str(Path(sys.executable).parent / "snakemake")


def _load(path: Path):
    spec = importlib.util.spec_from_file_location(path.stem, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


derive = _load(PROFILE / "derive_resources.py")


def _yaml(path: Path) -> dict:
    with path.open() as fh:
        return yaml.safe_load(fh)


def _ci(section: str) -> dict:
    return deep_merge(_yaml(ROOT / "config/config.yaml"), _yaml(ROOT / "config/ci.yaml"))[section]


def _limit(value: str) -> int:
    m = re.fullmatch(r"(\d+) \* attempt", str(value))
    assert m, f"resource {value!r} is not '<int> * attempt'"
    return int(m.group(1))


# ---------------------------------------------------------------- the profile


def test_every_rule_has_measured_resources_in_the_slurm_profile():
    """No rule falls back to the default resources; the values follow from the measurement
    table by the stated margins; no stale entries."""
    rules = set(derive.rules_in_workflow(ROOT))
    assert {"nr_shard", "fusion_point", "handover_shard", "tunnel_run", "paper"} <= rules
    # the Snakefile holds only targets (nothing to submit)
    snakefile = (ROOT / "workflow/Snakefile").read_text()
    assert not re.search(r"^\s+(script|shell|run|notebook|wrapper):", snakefile, flags=re.M)
    prof = _yaml(PROFILE / "config.yaml")
    assert prof["executor"] == "slurm" and prof["retries"] >= 1
    setres = prof["set-resources"]
    # every rule covered; an entry may precede its rule (a rule another engineer is adding)
    assert rules <= set(setres), f"rules without cluster resources: {sorted(rules - set(setres))}"
    table = derive.read_table()
    assert {r["rule"] for r in table} == set(setres)
    assert {r["source"] for r in table} <= {"benchmark", "rerun", "estimate"}
    want = derive.derive(table)
    for rule, res in setres.items():
        got = {k: _limit(res[k]) for k in ("mem_mb", "runtime")}
        assert got == want[rule], rule
    # the margins really are margins
    for r in table:
        assert want[r["rule"]]["mem_mb"] >= 2 * r["max_rss_mb_max"]
        assert want[r["rule"]]["runtime"] * 60 >= 3 * r["wall_s_max"]
    # grouped rules exist and each group has its components setting
    assert set(prof["groups"]) <= rules, sorted(set(prof["groups"]) - rules)
    assert set(prof["groups"].values()) == set(prof["group-components"])


def test_derivation_margins():
    rows = [
        {"rule": "a", "jobs": 1, "wall_s_max": 111.2, "max_rss_mb_max": 640.2, "source": "x"},
        {"rule": "b", "jobs": 1, "wall_s_max": 0.3, "max_rss_mb_max": 100.0, "source": "x"},
    ]
    assert derive.derive(rows) == {"a": {"mem_mb": 1500, "runtime": 6}, "b": {"mem_mb": 1000, "runtime": 5}}


def test_cluster_shards_are_valid_and_fit_the_work():
    """shards.yaml passes the schema and never asks for more shards than units of work."""
    shards = _yaml(PROFILE / "shards.yaml")
    cfg = deep_merge(_yaml(ROOT / "config/config.yaml"), shards)
    validate_config(cfg, load_schema(ROOT / "workflow/schemas/config.schema.yaml"))
    from railradio.nr.engine.simulate import scenario_from_config

    n_epochs = scenario_from_config(cfg["nr"]).trajectory.n_epochs
    assert cfg["nr"]["n_shards"] <= n_epochs
    assert cfg["nr"]["sensitivity"]["n_shards"] <= cfg["nr"]["sensitivity"]["epochs"]
    assert cfg["handover"]["sweep"]["n_batches"] <= cfg["handover"]["sweep"]["n_blocks"]
    # more shards than the 2-core default, or the file has no reason to exist
    base = _yaml(ROOT / "config/config.yaml")
    assert cfg["nr"]["n_shards"] > base["nr"]["n_shards"]
    assert cfg["handover"]["sweep"]["n_batches"] > base["handover"]["sweep"]["n_batches"]


def _dry_run_jobs(out: str) -> list[tuple[str, dict[str, str]]]:
    """(rule, resources) of every job in a dry run's output."""
    jobs = []
    for block in re.split(r"\n\s*\[[^\]]+\]\s*\n", out):
        m = re.search(r"^\s*(?:local)?rule (\w+):", block, flags=re.M)
        r = re.search(r"^\s*resources: (.*)$", block, flags=re.M)
        if m and r:
            jobs.append((m.group(1), dict(kv.split("=", 1) for kv in r.group(1).split(", "))))
    return jobs


@pytest.mark.slow
def test_slurm_dry_run_gives_every_job_its_rule_resources_and_cluster_shards(tmp_path):
    _copy_workflow(tmp_path)
    run = subprocess.run(
        [
            SNAKEMAKE,
            "all",
            "paper",
            "nr_imm_all",
            "fidelity",
            "-n",
            "--forceall",
            "--workflow-profile",
            "workflow/profiles/slurm",
        ],
        cwd=tmp_path,
        env={
            "PATH": str(Path(sys.executable).parent) + ":/usr/bin:/bin",
            "PYTHONPATH": str(tmp_path / "src"),
            "HOME": str(tmp_path),
        },
        capture_output=True,
        text=True,
        check=False,
        timeout=COMMAND_TIMEOUT_S,
    )
    out = run.stdout + run.stderr
    assert run.returncode == 0, out[-3000:]
    prof = _yaml(PROFILE / "config.yaml")
    targets = {"all", "nr_imm_all", "fidelity"}
    jobs = [(r, res) for r, res in _dry_run_jobs(out) if r not in targets]
    counts: dict[str, int] = {}
    for rule, res in jobs:
        counts[rule] = counts.get(rule, 0) + 1
        want = prof["set-resources"][rule]
        assert int(res["mem_mb"]) == _limit(want["mem_mb"]), (rule, res)
        assert int(res["runtime"]) == _limit(want["runtime"]), (rule, res)
        assert res["cpus_per_task"] == "1"
    assert set(counts) == set(derive.rules_in_workflow(tmp_path))  # every rule is in the DAG
    # the profile's configfiles took effect: cluster-sized shards
    shards, base = _yaml(PROFILE / "shards.yaml"), _yaml(ROOT / "config/config.yaml")
    assert counts["nr_shard"] == base["nr"]["realizations"] * shards["nr"]["n_shards"]
    assert counts["nr_fidelity_shard"] == shards["nr"]["fidelity"]["n_shards"]
    assert counts["handover_shard"] == (
        len(base["handover"]["sweep"]["speeds_kmh"]) * shards["handover"]["sweep"]["n_batches"]
    )
    for group in prof["group-components"]:
        assert f"Group job {group} " in out


# ---------------------------------------------------------------- nr: track shards


def test_nr_shards_cover_every_epoch_once():
    from railradio.nr.engine.epochs import shard_epochs

    for n_epochs in (7, 160, 2500, 5775):
        for n_shards in (1, 2, 3, 5, 12, 48, n_epochs):
            parts = [shard_epochs(n_epochs, n_shards, s) for s in range(n_shards)]
            # no empty shard while there are at least as many epochs as shards (more shards
            # than epochs give empty ones: shards.yaml must not ask for that, tested above)
            assert all(p.size > 0 for p in parts) or n_shards > n_epochs
            assert max(p.size for p in parts) - min(p.size for p in parts) <= 1
            np.testing.assert_array_equal(np.concatenate(parts), np.arange(n_epochs))
    with pytest.raises(ValueError, match="shard"):
        shard_epochs(10, 2, 2)


def test_nr_epochs_identical_whatever_the_shards(tmp_path):
    """Simulated shards written and read back as the workflow does (railradio.nr.study.runs.read_shards)
    give the same per-epoch outputs for 1, 2 and 3 shards."""
    from railradio.io import write_dataset
    from railradio.nr.engine.epochs import shard_epochs, simulate_epochs
    from railradio.nr.engine.simulate import scenario_from_config
    from railradio.nr.study.runs import read_shards
    from railradio.rng import spawn_key

    c = _ci("nr")
    scn = scenario_from_config(c)
    first, n = 100, 6  # the train is moving: every receiver sees bursts
    key = spawn_key("nr", 0)
    runs = {}
    for n_shards in (1, 2, 3):
        paths = []
        for s in range(n_shards):
            ds = simulate_epochs(scn, first + shard_epochs(n, n_shards, s), 5, key)
            paths.append(tmp_path / f"n{n_shards}_s{s}.nc")
            write_dataset(ds, paths[-1], {"n_shards": n_shards}, key, title="test shard")
        runs[n_shards] = read_shards(paths)
    ref = runs[1]
    assert ref.sizes["epoch"] == n and int(ref["n_detected"].sum()) > 0
    for n_shards in (2, 3):
        xr.testing.assert_equal(runs[n_shards], ref)
    other = simulate_epochs(scn, first + np.arange(2), 5, spawn_key("nr", 1))  # another realization
    assert not np.array_equal(other["peak"].values, ref["peak"].values[:, :2])


# ---------------------------------------------------------------- handover: batches


def test_handover_crossings_and_summary_identical_whatever_the_batches():
    from railradio.handover.engine import shard_blocks, simulate_blocks
    from railradio.handover.params import scenario_from_config
    from railradio.handover.summary import policy_metrics

    c = _ci("handover")
    scn = scenario_from_config(c).with_weights(2, 0.5)  # the cost grid's choice is another rule's
    pols = tuple(c["policies"])
    n_blocks, runs = 4, 40
    whole = simulate_blocks(scn, 350.0, 3, range(n_blocks), runs, pols)
    for n_batches in (2, 3, 4):
        parts = [
            simulate_blocks(scn, 350.0, 3, shard_blocks(n_blocks, n_batches, b), runs, pols) for b in range(n_batches)
        ]
        # as workflow/scripts/handover/summary.py joins them
        joined = xr.concat(parts, dim="run", data_vars="minimal")
        xr.testing.assert_identical(joined, whole)
        for p in pols:
            assert policy_metrics(joined, p) == policy_metrics(whole, p)
    other = simulate_blocks(scn, 350.0, 4, range(1), runs, pols)  # another seed
    assert not np.array_equal(other["joint__command_x_m"].values, whole["joint__command_x_m"].values[:runs])


@pytest.mark.slow
def test_handover_workflow_identical_for_one_and_two_batches(tmp_path):
    """The CI-scale workflow (adapters, params, NetCDF round trip, summary) gives the same
    per-crossing outcomes and summary with handover.sweep.n_batches = 1 and 2 (~17 s)."""
    from railradio.io import read_dataset

    wd = _copy_workflow(tmp_path)
    env = {
        "PATH": str(Path(sys.executable).parent) + ":/usr/bin:/bin",
        "HOME": str(tmp_path),
        "PYTHONPATH": str(wd / "src"),
        "MPLBACKEND": "Agg",
    }
    speeds = _ci("handover")["sweep"]["speeds_kmh"]
    out = {}
    for n_batches in (1, 2):
        (wd / "batches.yaml").write_text(f"handover:\n  sweep:\n    n_batches: {n_batches}\n")
        run = subprocess.run(
            [
                SNAKEMAKE,
                "results/handover/summary.nc",
                "-j1",
                "--workflow-profile",
                "workflow/profiles/default",
                "--configfile",
                "config/ci.yaml",
                "batches.yaml",
            ],
            cwd=wd,
            env=env,
            capture_output=True,
            text=True,
            check=False,
            timeout=PIPELINE_TIMEOUT_S,
        )
        assert run.returncode == 0, (run.stdout + run.stderr)[-3000:]
        shards = {
            v: xr.concat(
                [read_dataset(wd / f"results/handover/shards/v{v}/b{b}.nc") for b in range(n_batches)],
                dim="run",
                data_vars="minimal",
            )
            for v in speeds
        }
        out[n_batches] = (shards, read_dataset(wd / "results/handover/summary.nc"))
    for v in speeds:
        xr.testing.assert_equal(out[2][0][v], out[1][0][v])
    xr.testing.assert_equal(out[2][1], out[1][1])


# ---------------------------------------------------------------- fusion: chunks


def test_fusion_point_identical_whatever_the_chunks():
    from railradio.fusion.montecarlo import point_params, simulate_point, sweep_points
    from railradio.rng import spawn_key, stable_id

    point = {**sweep_points(_ci("fusion"), "reference")[0], "n_positions": 23, "n_trials": 300}
    params, key = point_params(point), spawn_key("fusion", stable_id(point))
    ref = simulate_point(params, 11, key, chunk_positions=23)
    for chunk in (1, 5, 50):
        xr.testing.assert_identical(simulate_point(params, 11, key, chunk_positions=chunk), ref)
    other = simulate_point(params, 12, key, chunk_positions=23)
    assert not np.array_equal(other["mse"].values, ref["mse"].values)


# ---------------------------------------------------------------- tunnel: realizations


def test_tunnel_realizations_identical_whatever_the_subset():
    """Monte Carlo realizations are keyed by their ID: any subset (a would-be shard) gives
    the same errors per realization as the whole set."""
    from railradio.tunnel.simulate import calibrate_separable, kf_realizations
    from railradio.tunnel.study import (
        cable_from_config,
        make_order,
        make_table,
        measurement_from_config,
        train_from_config,
        tunnel_from_config,
    )

    cfg = _ci("tunnel")
    table = make_table(cfg, "image", 7, make_order(cfg))
    tun = tunnel_from_config(cfg, table.attrs["shape"])
    cab, mm, tr = cable_from_config(cfg), measurement_from_config(cfg), train_from_config(cfg, "hst")
    r0 = calibrate_separable(table, tun, cab, tr, mm, "physical", cfg["tracking"], 3)
    args = (table, tun, cab, tr, mm, "physical", cfg["tracking"], 3, r0)
    head, tail = kf_realizations(*args, [1, 2, 3])
    for split in ([[1], [2, 3]], [[3, 1], [2]], [[3], [1], [2]]):
        rows = {}
        for group in split:
            h, t = kf_realizations(*args, group)
            rows.update({r: (h[i], t[i]) for i, r in enumerate(group)})
        np.testing.assert_array_equal(np.stack([rows[r][0] for r in (1, 2, 3)]), head)
        np.testing.assert_array_equal(np.stack([rows[r][1] for r in (1, 2, 3)]), tail)
    assert not np.array_equal(head[0], head[1])
