"""Does every job the slurm profile submits fit a node? (No job may pend forever.)

Runs Snakemake's dry run with the profile's settings, records what each submission would
request — single jobs and the profile's group jobs, whose requests Snakemake derives from
their members (jobs that could run side by side add up, unless the profile's local
``cpus_per_task`` limit stacks them one after another) — and compares every request with a
node of ``--cpus`` CPUs and ``--mem-mb`` MB. Exit status 1 names the jobs that do not fit.

    .venv/bin/python workflow/profiles/slurm/fit.py [--cpus 2] [--mem-mb 16000] [-- snakemake args]

Run from a copy of the workflow with no results (the dry run must see every job); the
default targets are the paper-scale DAG, ``all paper nr_imm_all``. Two differences between
a dry run and a cluster run are undone: the dry run is given an unbounded core count (a
cluster run has no ``--cores`` limit), and a group's request is computed as for a submitted
group (the dry run, a local execution, adds up the group's successive levels).
"""

from __future__ import annotations

import argparse
import json
import sys

NODE_CPUS = 2
NODE_MEM_MB = 16000
"""The stated node: the smallest a user is expected to run the profile on (this machine's
kind: 2 CPUs; 16 GB leaves room for the system on a 24 GB node)."""


UNBOUNDED_CORES = 1_000_000


def requests(targets: list[str], extra: list[str]) -> list[dict]:
    """What the slurm profile would submit for ``targets``: one entry per submission,
    ``{"name", "group", "jobs", "cpus", "mem_mb", "runtime_min"}``."""
    from snakemake.cli import main
    from snakemake.executors import dryrun
    from snakemake.resources import GroupResources

    seen: list[dict] = []

    def run_job(self, job):
        res = job.resources
        if job.is_group():  # as a submitted group computes it (a dry run is a local execution)
            res = GroupResources.basic_layered(
                toposorted_jobs=job.toposorted,
                constraints=job.global_resources,
                run_local=False,
                additive_resources=["runtime"],
                sortby=["runtime"],
            )
        cpus = res.get("cpus_per_task") or res.get("_cores") or 1
        seen.append(
            {
                "name": job.groupid if job.is_group() else job.rule.name,
                "group": job.is_group(),
                "jobs": len(job.jobs) if job.is_group() else 1,
                "cpus": int(cpus),
                "mem_mb": int(res.get("mem_mb", 0)),
                "runtime_min": int(res.get("runtime", 0)),
            }
        )
        return orig(self, job)

    orig = dryrun.Executor.run_job
    dryrun.Executor.run_job = run_job
    try:
        main(
            [
                *targets,
                "-n",
                "-q",
                "all",
                "--cores",
                str(UNBOUNDED_CORES),
                "--workflow-profile",
                "workflow/profiles/slurm",
                *extra,
            ]
        )
    except SystemExit as exc:
        if exc.code:
            raise
    finally:
        dryrun.Executor.run_job = orig
    return seen


def misfits(subs: list[dict], cpus: int = NODE_CPUS, mem_mb: int = NODE_MEM_MB) -> list[dict]:
    """The submissions that ask for more than a node has."""
    return [s for s in subs if s["cpus"] > cpus or s["mem_mb"] > mem_mb]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("snakemake_args", nargs="*", help="targets and options for Snakemake (after --)")
    ap.add_argument("--cpus", type=int, default=NODE_CPUS)
    ap.add_argument("--mem-mb", type=int, default=NODE_MEM_MB)
    ap.add_argument("--json", help="write every submission's request here")
    args = ap.parse_args()
    targets = [a for a in args.snakemake_args if not a.startswith("-")] or ["all", "paper", "nr_imm_all"]
    extra = [a for a in args.snakemake_args if a.startswith("-")]
    subs = requests(targets, extra)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(subs, fh, indent=1)
    bad = misfits(subs, args.cpus, args.mem_mb)
    groups = [s for s in subs if s["group"]]
    print(
        f"{len(subs)} submissions ({len(groups)} group jobs); largest: "
        f"{max(s['cpus'] for s in subs)} CPUs, {max(s['mem_mb'] for s in subs)} MB; "
        f"node: {args.cpus} CPUs, {args.mem_mb} MB"
    )
    for s in bad:
        print(f"does not fit: {s['name']} ({s['jobs']} jobs): {s['cpus']} CPUs, {s['mem_mb']} MB", file=sys.stderr)
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
