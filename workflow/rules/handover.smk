# Study `handover`: position-power joint handover decision vs A3 and distance triggers
# (source 004; docs/model/handover.md, our reconstruction of the lost equations).
# Chain: cost grid of (m, alpha) on its own runs -> shards of crossings per (speed, batch)
# with the selected weights -> summary per policy and speed -> figures + key numbers;
# one-at-a-time sensitivity cases on the reference speed's runs -> their summary.
from railradio.handover.engine import speed_label
from railradio.handover.params import SIM_SECTIONS
from railradio.handover.sensitivity import cases as handover_cases

HO = config["handover"]
HO_SIM = {k: HO[k] for k in SIM_SECTIONS}
HO_SWEEP = HO["sweep"]
HO_SENS = HO["sensitivity"]
HO_SPEEDS = [speed_label(v) for v in HO_SWEEP["speeds_kmh"]]
HO_BATCHES = range(HO_SWEEP["n_batches"])
HO_CASES = handover_cases(HO_SENS)
HO_FIGURES = {
    "handover_cost_vs_m": "results/handover/cost.nc",
    "handover_pingpong_vs_speed": "results/handover/summary.nc",
    "handover_rsrp_gap_vs_speed": "results/handover/summary.nc",
    "handover_delay_vs_speed": "results/handover/summary.nc",
    "handover_interruption_vs_speed": "results/handover/summary.nc",
    "handover_stages_vs_speed": "results/handover/summary.nc",
    "handover_sensitivity": "results/handover/sensitivity.nc",
}

register_figures("handover", list(HO_FIGURES))
KEY_NUMBER_FRAGMENTS.append("results/handover/key_numbers.json")
register_figures("handover_correction", ["handover_correction"])
KEY_NUMBER_FRAGMENTS.append("results/handover/correction_key_numbers.json")
HO_CORRECTION_SPEEDS = [v for v in (100, 350) if v in HO_SWEEP["speeds_kmh"]] or HO_SWEEP["speeds_kmh"][:1]


wildcard_constraints:
    ho_speed=r"\d+(\.\d+)?",
    batch=r"\d+",
    ho_case=r"[A-Za-z0-9_]+",


rule handover_cost:
    """Cost J(m, alpha) of the joint decision on its own runs (source Fig. 4)."""
    output:
        "results/handover/cost.nc",
    params:
        sim=HO_SIM,
        cost=HO["cost"],
        runs_per_block=HO_SWEEP["runs_per_block"],
        seed=config["seed"],
    log:
        "results/logs/handover/cost.log",
    benchmark:
        "results/benchmarks/handover/cost.tsv"
    resources:
        mem_mb=2000,
        runtime=20,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/handover/cost.py"


rule handover_shard:
    """Crossings of one (speed, batch) shard: per-handover outcomes of every policy."""
    input:
        cost="results/handover/cost.nc",
    output:
        "results/handover/shards/v{ho_speed}/b{batch}.nc",
    params:
        sim=HO_SIM,
        case={},
        policies=HO["policies"],
        speed_kmh=lambda w: float(w.ho_speed),
        n_blocks=HO_SWEEP["n_blocks"],
        n_batches=HO_SWEEP["n_batches"],
        runs_per_block=HO_SWEEP["runs_per_block"],
        seed=config["seed"],
    log:
        "results/logs/handover/shard_v{ho_speed}_b{batch}.log",
    benchmark:
        "results/benchmarks/handover/shard_v{ho_speed}_b{batch}.tsv"
    resources:
        mem_mb=1500,
        runtime=20,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/handover/shard.py"


rule handover_summary:
    """Rates (Wilson intervals) and means per policy and speed."""
    input:
        expand("results/handover/shards/v{ho_speed}/b{batch}.nc", ho_speed=HO_SPEEDS, batch=HO_BATCHES),
    output:
        "results/handover/summary.nc",
    params:
        dim="speed_kmh",
        groups=[v for v in HO_SPEEDS for _ in HO_BATCHES],
        policies=HO["policies"],
    log:
        "results/logs/handover/summary.log",
    benchmark:
        "results/benchmarks/handover/summary.tsv"
    resources:
        mem_mb=3000,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/handover/summary.py"


rule handover_sensitivity_shard:
    """One sensitivity case at the reference speed, on the sweep's first blocks."""
    input:
        cost="results/handover/cost.nc",
    output:
        "results/handover/sensitivity/{ho_case}/b{batch}.nc",
    params:
        sim=HO_SIM,
        case=lambda w: HO_CASES[w.ho_case],
        policies=HO["policies"],
        speed_kmh=float(HO_SENS["speed_kmh"]),
        n_blocks=HO_SENS["n_blocks"],
        n_batches=1,
        runs_per_block=HO_SWEEP["runs_per_block"],
        seed=config["seed"],
    log:
        "results/logs/handover/sensitivity_{ho_case}_b{batch}.log",
    benchmark:
        "results/benchmarks/handover/sensitivity_{ho_case}_b{batch}.tsv"
    resources:
        mem_mb=1500,
        runtime=20,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/handover/shard.py"


rule handover_sensitivity:
    """Rates and means per policy and sensitivity case."""
    input:
        expand("results/handover/sensitivity/{ho_case}/b0.nc", ho_case=list(HO_CASES)),
    output:
        "results/handover/sensitivity.nc",
    params:
        dim="case",
        groups=list(HO_CASES),
        cases=HO_CASES,
        policies=HO["policies"],
        speed_kmh=float(HO_SENS["speed_kmh"]),
    log:
        "results/logs/handover/sensitivity.log",
    benchmark:
        "results/benchmarks/handover/sensitivity.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/handover/summary.py"


rule handover_figure:
    """One figure of the handover study (source Fig. 4-8, sensitivity)."""
    input:
        lambda w: HO_FIGURES[w.name],
    output:
        pdf=report(
            "results/figures/{name}.pdf",
            caption="../report/handover_figures.rst",
            category="handover",
        ),
        png="results/figures/{name}.png",
    log:
        "results/logs/handover/figure_{name}.log",
    benchmark:
        "results/benchmarks/handover/figure_{name}.tsv"
    wildcard_constraints:
        name="|".join(HO_FIGURES),
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/handover/figure.py"


rule handover_correction:
    """The joint decision's power correction per node against the true deviations, at 100
    and 350 km/h on the sweep's first blocks (where its error comes from)."""
    input:
        cost="results/handover/cost.nc",
    output:
        nc="results/handover/correction.nc",
        json="results/handover/correction_key_numbers.json",
        pdf=report(
            "results/figures/handover_correction.pdf", caption="../report/handover_figures.rst", category="handover"
        ),
        png="results/figures/handover_correction.png",
    params:
        sim=HO_SIM,
        seed=config["seed"],
        speeds_kmh=HO_CORRECTION_SPEEDS,
        n_blocks=min(4, HO_SWEEP["n_blocks"]),
        runs_per_block=HO_SWEEP["runs_per_block"],
    log:
        "results/logs/handover/correction.log",
    benchmark:
        "results/benchmarks/handover/correction.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/handover/correction.py"


rule handover_key_numbers:
    """Key numbers handover.* (ours beside the source's claims)."""
    input:
        summary="results/handover/summary.nc",
        cost="results/handover/cost.nc",
        sensitivity="results/handover/sensitivity.nc",
    output:
        "results/handover/key_numbers.json",
    params:
        sim=HO_SIM,
    log:
        "results/logs/handover/key_numbers.log",
    benchmark:
        "results/benchmarks/handover/key_numbers.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/handover/key_numbers.py"
