"""The slurm profile on a real scheduler: a single-node SLURM on this machine
(workflow/profiles/slurm/local-cluster.sh), real ``sbatch`` submissions.

* the fusion study at CI scale through ``--workflow-profile workflow/profiles/slurm``:
  every job (its group job included) is submitted, run and collected, and the key numbers
  equal the session's local CI-scale run's. One study, not the whole CI-scale pipeline:
  through the scheduler every job pays a Snakemake start and a status poll (fusion:
  ~1.5 min; fusion and handover: 10 min), which CI's time limit cannot hold for all of it;
  fusion has the profile's groups and each kind of job the others have;
* a job killed by SLURM for exceeding its time limit is retried with the doubled limit
  (the profile's ``retries: 1`` and ``runtime: "N * attempt"``);
* every submission of the paper-scale DAG fits a 2-CPU, 16 GB node (``fit.py``), and the
  check can fail (the groups without the profile's CPU limit do not fit).

SLURM needs root and Debian's ``slurm-wlm`` and ``munge``: the tests are skipped where they
are missing, unless ``RAILRADIO_REQUIRE_SLURM=1`` (set by ``.ci/run``, which installs them).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from railradio.keynumbers import compare

from .conftest import COMMAND_TIMEOUT_S, ROOT, SNAKEMAKE, copy_workflow, workflow_env

LOCAL_CLUSTER = ROOT / "workflow/profiles/slurm/local-cluster.sh"
FIT = ROOT / "workflow/profiles/slurm/fit.py"
SLICE = "results/fusion/key_numbers.json"
FAST_POLL = [
    "--slurm-status-command",
    "squeue",
    "--slurm-init-seconds-before-status-checks",
    "5",
    "--seconds-between-status-checks",
    "5",
]
"""The local cluster has no accounting database (squeue reports the states) and answers at
once, so Snakemake may poll it often."""


def _have_slurm() -> bool:
    return os.geteuid() == 0 and all(shutil.which(t) for t in ("slurmctld", "slurmd", "munged", "sbatch"))


@pytest.fixture(scope="module")
def local_cluster():
    if not _have_slurm():
        if os.environ.get("RAILRADIO_REQUIRE_SLURM") == "1":
            pytest.fail("SLURM (slurm-wlm, munge) and root are required here (RAILRADIO_REQUIRE_SLURM=1)")
        pytest.skip("needs root and Debian's slurm-wlm and munge")
    run = subprocess.run(
        [str(LOCAL_CLUSTER), "start"], capture_output=True, text=True, timeout=COMMAND_TIMEOUT_S, check=False
    )
    assert run.returncode == 0, run.stdout + run.stderr
    yield
    subprocess.run([str(LOCAL_CLUSTER), "stop"], capture_output=True, timeout=COMMAND_TIMEOUT_S, check=False)
    # its configuration goes with it: one naming a stopped controller makes every later
    # Snakemake start wait ~9 s (the executor plugin's `scontrol show config`)
    conf = Path("/etc/slurm/slurm.conf")
    assert not (conf.exists() and "railradio's local-cluster.sh" in conf.read_text().splitlines()[0]), conf


def _squeue_states(job_ids: list[str]) -> dict[str, tuple[str, str]]:
    """{job id: (state, time limit)} from squeue (finished jobs stay there for MinJobAge)."""
    out = subprocess.run(
        ["squeue", "-h", "-a", "-t", "all", "-o", "%i|%T|%l"],
        capture_output=True,
        text=True,
        check=True,
        timeout=COMMAND_TIMEOUT_S,
    ).stdout
    rows = dict(line.split("|", 1) for line in out.split())
    return {j: tuple(rows[j].split("|")) for j in job_ids if j in rows}


def _submitted(log: str) -> list[str]:
    """The SLURM job ids Snakemake reports submitting, in order."""
    return [line.split("SLURM jobid ")[1].split()[0] for line in log.splitlines() if "SLURM jobid " in line]


SLOW_ONCE = """
rule all:
    input: "done.txt"

rule slow_once:
    output: "done.txt"
    resources: runtime=lambda wildcards, attempt: attempt, mem_mb=200
    shell: "if [ -e first_attempt ]; then touch {output}; else touch first_attempt; sleep 600; fi"
"""


@pytest.fixture(scope="module")
def retry_run(local_cluster, tmp_path_factory):
    """The time-limit workflow, started at once and left to SLURM while the fusion study
    runs (its first attempt only sleeps: most of the test's time is SLURM's time limit)."""
    wd = tmp_path_factory.mktemp("retry")
    shutil.copytree(ROOT / "workflow/profiles/slurm", wd / "workflow/profiles/slurm")
    (wd / "Snakefile").write_text(SLOW_ONCE)
    prof = wd / "workflow/profiles/slurm/config.yaml"
    cfg = yaml.safe_load(prof.read_text())
    cfg.pop("configfiles", None)  # the study's shard counts: not this workflow's
    prof.write_text(yaml.safe_dump(cfg))
    proc = subprocess.Popen(
        [SNAKEMAKE, "--workflow-profile", "workflow/profiles/slurm", *FAST_POLL],
        cwd=wd,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    yield wd, proc
    if proc.poll() is None:
        proc.kill()


@pytest.mark.slow
@pytest.mark.ci_run_last
def test_the_fusion_study_through_slurm_gives_the_local_key_numbers(request, local_cluster, retry_run, tmp_path):
    wd = copy_workflow(tmp_path)
    cmd = [
        SNAKEMAKE,
        SLICE,
        "--workflow-profile",
        "workflow/profiles/slurm",
        "--configfile",
        "config/ci.yaml",
        "--jobs",
        "4",
        *FAST_POLL,
    ]
    run = subprocess.run(cmd, cwd=wd, env=workflow_env(wd), capture_output=True, text=True, check=False, timeout=1200)
    log = run.stdout + run.stderr
    assert run.returncode == 0, log[-5000:]
    submitted = _submitted(log)
    assert len(submitted) >= 5, log[-3000:]  # real sbatch submissions
    assert any("group_fusion_post" in line for line in log.splitlines()), "the profile's group was not submitted"
    states = _squeue_states(submitted)
    assert {s for s, _ in states.values()} == {"COMPLETED"}, states
    ours = json.loads((wd / SLICE).read_text())
    local = json.loads((request.getfixturevalue("ci_run") / SLICE).read_text())
    assert len(ours) >= 10  # the fusion study publishes 10 keys
    assert compare(ours, local, mode="reproduce") == []
    assert {k: v["value"] for k, v in ours.items()} == {k: v["value"] for k, v in local.items()}


@pytest.mark.slow
def test_a_job_killed_at_its_time_limit_is_retried_with_the_doubled_limit(retry_run):
    """The profile's policy (``retries: 1``, ``runtime: "N * attempt"``) on a rule that
    outlives its 1-minute limit on the first attempt only: SLURM kills it (TIMEOUT) and
    Snakemake submits it again with a 2-minute limit, which completes."""
    wd, proc = retry_run
    log, _ = proc.communicate(timeout=900)
    assert proc.returncode == 0, log[-5000:]
    assert (wd / "done.txt").exists()
    submitted = _submitted(log)
    assert len(submitted) == 2, log[-3000:]
    states = _squeue_states(submitted)
    assert states[submitted[0]] == ("TIMEOUT", "1:00"), states
    assert states[submitted[1]] == ("COMPLETED", "2:00"), states


def _fit(wd: Path, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(FIT), "--json", str(wd / "fit.json"), "--", *extra],
        cwd=wd,
        env=workflow_env(wd),
        capture_output=True,
        text=True,
        check=False,
        timeout=COMMAND_TIMEOUT_S,
    )


def test_every_paper_scale_submission_fits_a_two_cpu_node(tmp_path):
    """No submission of the paper-scale DAG asks for more than a 2-CPU, 16 GB node (fit.py's
    stated node): the groups ask for one CPU and their largest member's memory. Without the
    profile's CPU limit the same groups add up their members and do not fit."""
    wd = copy_workflow(tmp_path)
    run = _fit(wd)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-3000:]
    subs = json.loads((wd / "fit.json").read_text())
    groups = {s["name"]: s for s in subs if s["group"]}
    assert set(groups) == {"fusion_post", "nr_post", "handover_post", "tunnel_post", "paper_post"}
    assert all(g["cpus"] == 1 and g["jobs"] >= 2 for g in groups.values()), groups
    assert max(s["cpus"] for s in subs) <= 2 and max(s["mem_mb"] for s in subs) <= 16000
    prof = wd / "workflow/profiles/slurm/config.yaml"
    cfg = yaml.safe_load(prof.read_text())
    del cfg["resources"], cfg["set-resource-scopes"]
    prof.write_text(yaml.safe_dump(cfg))
    run = _fit(wd)
    assert run.returncode == 1 and "does not fit: fusion_post" in run.stderr, run.stderr[-3000:]
