# Study `chain`: one railway, one chain (docs/model/chain.md). The nr study's tracked
# along-track position error (results/nr/imm/{real}.nc, the source's EKF on the robust
# receiver's gated AOD+TOA) replaces the handover study's assumed GNSS/INS error, beside a
# Gauss-Markov sweep of the error sigma. Reads the nr IMM/track files and the handover cost
# grid; simulates crossings with the handover engine's blocks.
# Chain: shards of blocks (every input, every policy) -> summary -> figure + key numbers.
from railradio.chain.params import params_from_config

CH = config["chain"]
CH_PARAMS = params_from_config(CH)
CH_BATCHES = range(CH["n_batches"])
CH_FIGURE_MAX_SIGMA_M = CH["figure_max_sigma_m"]

register_figures("chain", ["chain_success_vs_sigma"])
KEY_NUMBER_FRAGMENTS.append("results/chain/key_numbers.json")


rule chain_shard:
    """Crossings of one shard of blocks at the chain speed: every position input, every policy."""
    input:
        cost="results/handover/cost.nc",
        nr=expand("results/nr/imm/{real}.nc", real=NR_PLAN.realizations),
    output:
        "results/chain/shards/b{batch}.nc",
    params:
        sim=HO_SIM,
        chain=CH,
        n_batches=CH["n_batches"],
        runs_per_block=HO_SWEEP["runs_per_block"],
        seed=config["seed"],
    log:
        "results/logs/chain/shard_b{batch}.log",
    benchmark:
        "results/benchmarks/chain/shard_b{batch}.tsv"
    resources:
        mem_mb=1500,
        runtime=20,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/chain/shard.py"


rule chain_summary:
    """Success / ping-pong rates per (position input, policy) with clustered Wilson intervals."""
    input:
        expand("results/chain/shards/b{batch}.nc", batch=CH_BATCHES),
    output:
        "results/chain/summary.nc",
    log:
        "results/logs/chain/summary.log",
    benchmark:
        "results/benchmarks/chain/summary.tsv"
    resources:
        mem_mb=2000,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/chain/summary.py"


rule chain_key_numbers:
    """Key numbers chain.*: nr-driven success and ping-pong, the sigma crossover, nr error statistics."""
    input:
        summary="results/chain/summary.nc",
        nr=expand("results/nr/imm/{real}.nc", real=NR_PLAN.realizations),
        track=expand("results/nr/track/{real}.nc", real=NR_PLAN.realizations),
    output:
        "results/chain/key_numbers.json",
    params:
        chain=CH,
        receiver=NR["imm"]["receiver"],
        figure_max_sigma_m=CH_FIGURE_MAX_SIGMA_M,
    log:
        "results/logs/chain/key_numbers.log",
    benchmark:
        "results/benchmarks/chain/key_numbers.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/chain/key_numbers.py"


rule chain_figure:
    """Handover success vs position-error sigma, A3 reference, nr-driven points."""
    input:
        "results/chain/summary.nc",
    output:
        pdf=report(
            "results/figures/chain_success_vs_sigma.pdf",
            caption="../report/chain_success_vs_sigma.rst",
            category="chain",
        ),
        png="results/figures/chain_success_vs_sigma.png",
    params:
        figure_max_sigma_m=CH_FIGURE_MAX_SIGMA_M,
    log:
        "results/logs/chain/figure.log",
    benchmark:
        "results/benchmarks/chain/figure.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/chain/figure.py"
