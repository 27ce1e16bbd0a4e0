"""The pipeline end to end at CI scale, in a private copy of the workflow.

Each test works in a temporary copy of workflow/ (its Snakefile), config/, paper/ and src/
(with PYTHONPATH pointing at the copy, so a test may edit library code without touching
the repository).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import time
from pathlib import Path

import pytest
import xarray as xr

from railradio.codedeps import script_closure
from railradio.keynumbers import compare

from .conftest import COMMAND_TIMEOUT_S, ROOT, SNAKEMAKE, smk
from .conftest import copy_workflow as _copy_workflow
from .conftest import workflow_env as _env
from .test_codedeps import rule_scripts

pytestmark = pytest.mark.slow
EXPECTED = ROOT / "tests/expected/key_numbers_ci.json"


def job_counts(output: str) -> dict[str, int]:
    """Parse Snakemake's 'Job stats' table."""
    counts, inside = {}, False
    for line in output.splitlines():
        if line.startswith("Job stats"):
            inside = True
            continue
        if inside:
            parts = line.split()
            if len(parts) == 2 and parts[1].isdigit():
                if parts[0] == "total":
                    break
                counts[parts[0]] = int(parts[1])
    return counts


def rerun_reasons(output: str) -> dict[str, str]:
    """rule -> Snakemake's reason(s) for re-running its jobs, from a dry run's output."""
    out: dict[str, str] = {}
    rule = None
    for line in output.splitlines():
        m = re.match(r"^(?:local)?rule (\w+):", line)
        if m:
            rule = m.group(1)
        elif rule and line.strip().startswith("reason:"):
            out[rule] = out.get(rule, "") + line.strip()[len("reason:") :]
    return out


def _numbers(wd: Path) -> dict:
    return json.loads((wd / "results/key_numbers.json").read_text())


def test_lint_is_clean():
    run = subprocess.run(
        [SNAKEMAKE, "--lint"], cwd=ROOT, capture_output=True, text=True, check=False, timeout=COMMAND_TIMEOUT_S
    )
    assert run.returncode == 0, run.stdout + run.stderr


def test_paper_scale_dag_resolves(tmp_path):
    wd = _copy_workflow(tmp_path)
    run = smk(wd, "all", "-n", ci=False, timeout=COMMAND_TIMEOUT_S)
    counts = job_counts(run.stdout + run.stderr)
    # 10 distances + 12 TDOA errors + 10 AOA errors + the reference point
    assert counts["fusion_point"] == 33 and counts["fusion_figure"] == 3
    # the figures of the published nr records: `all` runs their targets
    assert counts["nr_map_cell"] == 24 and counts["nr_map_key_numbers"] == 1 and counts["nr_case_key_numbers"] == 1


def test_reproduction_reads_the_nr_records_only_while_they_are_current(tmp_path):
    """`numbers` at paper scale (what `make reproduce` runs) merges the published map and
    cases records instead of running them; a changed config of one makes its record stale
    and brings back its jobs only."""

    def numbers_jobs() -> dict[str, int]:
        run = smk(wd, "numbers", "-n", ci=False, timeout=COMMAND_TIMEOUT_S)
        return job_counts(run.stdout + run.stderr)

    wd = _copy_workflow(tmp_path)
    counts = numbers_jobs()
    assert counts["nr_shard"] == 12 and counts["nr_imm"] == 3
    # the map's and the cases' runs stay out; the map dataset is built from the record's fragment
    assert not [r for r in counts if r.startswith(("nr_map_", "nr_case_")) and r != "nr_map_dataset"], counts
    assert counts["nr_map_dataset"] == 1
    cfg = wd / "config/config.yaml"
    text = cfg.read_text(encoding="utf-8")
    cfg.write_text(text.replace("n_boot: 1000", "n_boot: 999"), encoding="utf-8")
    counts = numbers_jobs()
    assert counts["nr_map_key_numbers"] == 1 and counts["nr_map_cell"] == 24
    assert not [r for r in counts if r.startswith("nr_case_")], counts
    cfg.write_text(text.replace("epochs: 2500 ", "epochs: 2400 "), encoding="utf-8")
    counts = numbers_jobs()
    assert counts["nr_case_key_numbers"] == 1
    assert not [r for r in counts if r.startswith("nr_map_") and r != "nr_map_dataset"], counts


def test_slurm_profile_dry_run_resolves(tmp_path):
    wd = _copy_workflow(tmp_path)
    run = subprocess.run(
        [SNAKEMAKE, "figures", "-n", "--workflow-profile", "workflow/profiles/slurm"],
        cwd=wd,
        env=_env(wd),
        capture_output=True,
        text=True,
        check=False,
        timeout=COMMAND_TIMEOUT_S,
    )
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    assert job_counts(run.stdout + run.stderr)["fusion_point"] == 32  # figures: no reference point


@pytest.mark.parametrize(
    ("override", "key"),
    [
        ("seed: 10.0\n", "seed"),  # a float where an integer belongs (the schema)
        ("fusion:\n  sweeps:\n    d_m: []\n", "fusion.sweeps.d_m"),
        ("nr:\n  n_shards: 500\n", "nr.n_shards"),  # more shards than the CI run's 160 epochs
        ("handover:\n  sweep:\n    n_batches: 3\n", "handover.sweep.n_batches"),  # more batches than blocks
        (
            "nr:\n  sensitivity:\n    cases:\n      loud:\n        radio: {tx_power_dbm: 900}\n",
            "nr.sensitivity.cases.loud.radio.tx_power_dbm",
        ),
    ],
)
def test_bad_config_stops_before_any_job(tmp_path, override, key):
    wd = _copy_workflow(tmp_path)
    (wd / "bad.yaml").write_text(override)
    run = subprocess.run(
        [SNAKEMAKE, "all", "-j1", "--configfile", "config/ci.yaml", "bad.yaml"],
        cwd=wd,
        env=_env(wd),
        capture_output=True,
        text=True,
        check=False,
        timeout=COMMAND_TIMEOUT_S,
    )
    assert run.returncode != 0
    assert f"config key '{key}'" in run.stderr + run.stdout
    assert "Allowed:" in run.stderr + run.stdout
    assert not (wd / "results").exists()


def test_nested_command_line_config_is_named_and_a_top_level_one_is_taken(tmp_path):
    """``--config nr={...}`` would reach the schema as strings ("'8' is not of type
    'integer'"): the workflow stops naming the cause and ``--configfile``; ``seed=7`` works."""
    wd = _copy_workflow(tmp_path)

    def dry(config):
        return smk(wd, "figures", "-n", "--config", config, check=False, timeout=COMMAND_TIMEOUT_S)

    run = dry("nr={'n_shards': 8}")
    out = run.stdout + run.stderr
    assert run.returncode != 0 and "--config nr=" in out and "--configfile my.yaml" in out, out[-2000:]
    assert "is not of type" not in out
    run = dry("seed=7")
    assert run.returncode == 0, (run.stdout + run.stderr)[-2000:]
    assert not (wd / "results").exists()


def test_ci_key_numbers_match_expected(ci_run):
    msgs = compare(_numbers(ci_run), json.loads(EXPECTED.read_text()), mode="reproduce")
    assert msgs == [], "\n".join(msgs)


def test_ci_numbers_consistent_with_published_paper_scale(ci_run):
    """The CI-scale Monte Carlo agrees with paper/numbers.json within both MC errors."""
    paper = json.loads((ROOT / "paper/numbers.json").read_text())
    ours = _numbers(ci_run)
    keys = [k for k in paper if k.startswith("fusion.d1500.")]
    assert keys
    msgs = compare({k: ours[k] for k in keys}, {k: paper[k] for k in keys}, mode="statistical", n_sigma=5.0)
    # the CRLB is exact, but CI averages it over fewer positions: allow 0.5 %
    msgs = [m for m in msgs if not m.startswith("fusion.d1500.crlb_m")]
    assert abs(ours["fusion.d1500.crlb_m"]["value"] / paper["fusion.d1500.crlb_m"]["value"] - 1) < 5e-3
    assert msgs == [], "\n".join(msgs)


def test_intermediates_are_self_explaining(ci_run):
    paths = sorted((ci_run / "results/fusion").rglob("*.nc"))
    assert len(paths) == 4 + 4 + 4 + 1 + 3
    nr_paths = sorted(
        p for p in (ci_run / "results/nr").rglob("*.nc") if "cases" not in p.parts and "map" not in p.parts
    )
    # trajectory, samples, 2 calibration + 2 evaluation shards, 1 track, 1 bounds, 1 IMM/RTS, the q band,
    # the along-track study
    assert len(nr_paths) == 1 + 1 + 2 + 2 + 1 + 1 + 1 + 1 + 1
    case_paths = sorted((ci_run / "results/nr/cases").rglob("*.nc"))
    # 14 cases with their own bursts: 2 calibration + 1 evaluation shard, 1 track each;
    # 7 cases that read another run's bursts (w_distance, sweep_ref, the 4 clock-sync cases,
    # panels_200m_point): their track only
    assert len(case_paths) == 14 * (2 + 1 + 1) + 7
    map_paths = sorted((ci_run / "results/nr/map").rglob("*.nc"))
    # the map's 24 cells: 21 with their own segment bursts (one shard each at CI scale: 15
    # M_T x data cells, the 4 search-window cells, the SSS template and the sanity row; the
    # default and the selection-only cells read others'), 22 calibration runs (one per burst
    # set), 24 tracks, and the map as one dataset
    assert len(map_paths) == 21 + 22 + 24 + 1
    assert ci_run / "results/nr/map/reproduction_map.nc" in map_paths
    paths += nr_paths + case_paths + map_paths
    for study, n_min in (("handover", 10), ("tunnel", 10), ("sens/fusion", 5), ("chain", 1)):
        found = sorted((ci_run / "results" / study).rglob("*.nc"))
        assert len(found) >= n_min, (study, len(found))
        paths += found
    for p in paths:
        with xr.open_dataset(p) as ds:
            for name, var in {**ds.data_vars, **ds.coords}.items():
                assert "units" in var.attrs and "long_name" in var.attrs, (p, name)
            for attr in ("config_json", "config_sha256", "seed_spawn_key", "railradio_version", "git_commit"):
                assert attr in ds.attrs, (p, attr)
    for name in (
        "fusion_rmse_vs_distance",
        "fusion_rmse_vs_tdoa_error",
        "fusion_rmse_vs_aoa_error",
        "nr_trajectory",
        "nr_burst_correlation",
        "nr_measurement_error_cdf",
        "nr_position_error_cdf",
        "nr_position_error_vs_time",
        "nr_sensitivity",
        "nr_imm_lag",
        "nr_q_band",
        "nr_along_track",
        "nr_reproduction_map",
        "handover_cost_vs_m",
        "handover_pingpong_vs_speed",
        "handover_rsrp_gap_vs_speed",
        "handover_delay_vs_speed",
        "handover_interruption_vs_speed",
        "tunnel_rssi_map",
        "tunnel_delay_spread",
        "tunnel_gdop",
        "tunnel_position_error_cdf",
        "tunnel_ray_engines",
        "tunnel_source_vs_physical",
        "tunnel_sensitivity",
        "nr_sweeps",
        "fusion_sensitivity",
        "chain_success_vs_sigma",
    ):
        assert (ci_run / f"results/figures/{name}.pdf").stat().st_size > 1000
    tex = (ci_run / "results/paper/numbers.tex").read_text()
    assert r"\@namedef{kn@fusion.d1500.rmse_fused_m}" in tex


def test_only_affected_rules_rerun(ci_run, tmp_path):
    wd = tmp_path / "wd"
    shutil.copytree(ci_run, wd, symlinks=True)
    assert job_counts(smk(wd, "all", "-n").stdout) == {}  # nothing to do
    # one AOA sweep value changes: its point, that sweep, its figure, the numbers
    ci = (wd / "config/ci.yaml").read_text().replace("sigma_aoa_rad: [0.005,", "sigma_aoa_rad: [0.004,")
    (wd / "config/ci.yaml").write_text(ci)
    counts = job_counts(smk(wd, "all", "-n").stdout)
    assert counts == {
        "all": 1,
        "fusion_point": 1,
        "fusion_sweep": 1,
        "fusion_figure": 1,
        "fusion_key_numbers": 1,
        "key_numbers": 1,
    }, counts
    # a plotting change re-runs the figures only, never a simulation; a comment or a
    # docstring re-runs nothing (the code hashes hold what runs: railradio.codedeps.file_digest)
    (wd / "config/ci.yaml").write_text((ci_run / "config/ci.yaml").read_text())
    fig = wd / "src/railradio/fusion/figures.py"
    original = fig.read_text()
    fig.write_text(original + "\n# a comment\n")
    assert job_counts(smk(wd, "all", "-n").stdout) == {}
    fig.write_text(original + "\n_COSMETIC = True\n")
    counts = job_counts(smk(wd, "all", "-n").stdout)
    assert counts == {"all": 1, "fusion_figure": 3}, counts
    fig.write_text(original)
    # a library change re-runs every rule whose script reaches the module, and only those
    # (nr/keys.py: before the hashes were derived, nr_figures and nr_imm_figure stayed stale)
    keys = wd / "src/railradio/nr/study/keys.py"
    keys.write_text(keys.read_text() + "\n_CHANGED = True\n")
    reasons = rerun_reasons(smk(wd, "all", "-n").stdout)
    outside_all = {"nr_fidelity", "nr_fidelity_shard"}  # target `fidelity` only: not in this dry run's DAG
    want = {r for r, s in rule_scripts().items() if "railradio.nr.study.keys" in script_closure(s)} - outside_all
    assert {"nr_figures", "nr_imm_figure", "nr_key_numbers"} <= want
    assert want <= set(reasons), sorted(want - set(reasons))  # every rule that runs nr/keys.py
    # (Snakemake names one reason per job: a rule downstream of another re-run may show that one)
    assert {r for r, why in reasons.items() if "Params have changed" in why} <= want, reasons
    assert all("Input files updated by another job" in why for r, why in reasons.items() if r not in want)


@pytest.mark.ci_run_last
def test_interrupted_run_leaves_nothing_half_written_and_resumes_to_the_same_numbers(request, tmp_path):
    """A -j1 run of the fusion study killed after two Monte Carlo points leaves no partial
    file; resumed at -j1 it finishes the rest, and its numbers and sweeps equal those of
    the session's uninterrupted -j2 run (same config: identical at any -j)."""
    wd = _copy_workflow(tmp_path)
    cmd = [
        SNAKEMAKE,
        "fusion",
        "-j1",
        "--workflow-profile",
        "workflow/profiles/default",
        "--configfile",
        "config/ci.yaml",
    ]
    # SIGINT at its default in the run, as at a terminal: a shell that starts the test suite
    # in the background (`cmd &`) hands its children SIGINT ignored, and Snakemake would then
    # finish the run instead of stopping
    proc = subprocess.Popen(
        cmd,
        cwd=wd,
        env=_env(wd),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    points = wd / "results/fusion/points"
    deadline = time.time() + 120
    try:
        while time.time() < deadline and len(list(points.rglob("*.nc"))) < 2:
            time.sleep(0.05)
        os.killpg(proc.pid, signal.SIGINT)
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode != 0
    n_done = len(list(points.rglob("*.nc")))
    assert not list((wd / "results").rglob("*.part"))
    for p in points.rglob("*.nc"):  # whatever exists is whole
        xr.open_dataset(p).close()
    run = smk(wd, "fusion", "-j1")
    n_points = len(list(points.rglob("*.nc")))
    redone = job_counts(run.stdout + run.stderr).get("fusion_point", 0)
    # the rest, plus at most the point whose file was renamed into place as the run was
    # stopped, before Snakemake recorded it
    assert n_points - n_done <= redone <= n_points - n_done + 1, (redone, n_points, n_done)
    ci_run = request.getfixturevalue("ci_run")
    for frag in ("results/fusion/key_numbers.json", "results/sens/fusion/key_numbers.json"):
        assert json.loads((wd / frag).read_text()) == json.loads((ci_run / frag).read_text()), frag
    for sweep in ("d_m", "sigma_tdoa_us", "sigma_aoa_rad"):
        with (
            xr.open_dataset(wd / f"results/fusion/sweep_{sweep}.nc") as a,
            xr.open_dataset(ci_run / f"results/fusion/sweep_{sweep}.nc") as b,
        ):
            xr.testing.assert_equal(a, b)


def test_paper_builds_without_undefined_references(ci_run):
    """The manuscript compiles from the CI run's numbers, figures and config macros, with
    no undefined key number, config value, reference or citation. ``make test`` needs
    LaTeX (``.ci/run`` installs it); RAILRADIO_SKIP_PAPER=1 skips this on a machine without."""
    if shutil.which("latexmk") is None:
        if os.environ.get("RAILRADIO_SKIP_PAPER") == "1":
            pytest.skip("latexmk not installed and RAILRADIO_SKIP_PAPER=1")
        pytest.fail(
            "latexmk is not installed: apt-get install latexmk texlive-latex-recommended "
            "texlive-latex-extra texlive-fonts-recommended texlive-science (or set "
            "RAILRADIO_SKIP_PAPER=1)"
        )
    smk(ci_run, "paper", "-j2")
    pdf = ci_run / "results/paper/main.pdf"
    assert pdf.read_bytes()[:5] == b"%PDF-" and pdf.stat().st_size > 10_000
    log = (ci_run / "results/paper/main.log").read_text(errors="replace")
    assert not re.search(r"undefined|Undefined control sequence", log), re.findall(r".*undefined.*", log)[:5]
    assert "LaTeX Warning: Reference" not in log and "LaTeX Warning: Citation" not in log
    assert "Package railradio Error" not in log
