# Tracking that does not lag (docs/model/nr.md §6): the nr study's EKF beside an
# IMM (quiet + manoeuvre white-jerk models) and an RTS smoother, around the trajectory's
# acceleration changes. Reads the nr shards and calibration; simulates nothing.

register_figures("nr_imm", ["nr_imm_lag"])
KEY_NUMBER_FRAGMENTS.append("results/nr/imm/key_numbers.json")


rule nr_imm:
    """EKF (the source's, calibrated), IMM and RTS-smoothed EKF of one realization."""
    input:
        shards=expand("results/nr/estimates/{{real}}/s{shard}.nc", shard=range(NR["n_shards"])),
        calibration="results/nr/calibration.json",
    output:
        "results/nr/imm/{real}.nc",
    params:
        sim=plain(NR_PLAN.sim),
        tracker=NR["tracker"],
        imm=NR["imm"],
        selection=plain(NR_PLAN.selection),
    wildcard_constraints:
        real=r"r\d+",
    log:
        "results/logs/nr/imm_{real}.log",
    benchmark:
        "results/benchmarks/nr/imm_{real}.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_imm/imm.py"


rule nr_imm_key_numbers:
    """Key numbers nr.track.{ekf,imm,rts}.* pooled over the realizations, with their spread."""
    input:
        expand("results/nr/imm/{real}.nc", real=NR_PLAN.realizations),
    output:
        "results/nr/imm/key_numbers.json",
    params:
        window_s=NR["imm"]["window_s"],
    log:
        "results/logs/nr/imm_key_numbers.log",
    benchmark:
        "results/benchmarks/nr/imm_key_numbers.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_imm/key_numbers.py"


rule nr_imm_figure:
    """Error, lag and IMM mode probability around each acceleration change."""
    input:
        expand("results/nr/imm/{real}.nc", real=NR_PLAN.realizations),
    output:
        pdf=report(
            "results/figures/nr_imm_lag.pdf",
            caption="../report/nr_imm_lag.rst",
            category="nr",
        ),
        png="results/figures/nr_imm_lag.png",
    params:
        window_s=NR["imm"]["figure_window_s"],
    log:
        "results/logs/nr/imm_figure.log",
    benchmark:
        "results/benchmarks/nr/imm_figure.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_imm/figure.py"
