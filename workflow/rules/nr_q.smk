# q as a band (docs/model/nr.md §6): the process-noise intensities the calibration run can
# not tell apart, and the headline tracker's accuracy over them. Reads the nr shards and
# calibration; simulates nothing.

register_figures("nr_q", ["nr_q_band"])
KEY_NUMBER_FRAGMENTS.append("results/nr/q_band/key_numbers.json")


rule nr_q_band:
    """The headline tracker at every q its calibration tried: cost, band, accuracy."""
    input:
        cal=expand("results/nr/estimates/cal/s{shard}.nc", shard=range(NR_PLAN.n_cal_shards)),
        runs=expand("results/nr/estimates/{real}/s{shard}.nc", real=NR_PLAN.realizations, shard=range(NR["n_shards"])),
        calibration="results/nr/calibration.json",
    output:
        nc="results/nr/q_band/q_band.nc",
        numbers="results/nr/q_band/key_numbers.json",
    params:
        sim=plain(NR_PLAN.sim),
        tracker=NR["tracker"],
        selection=plain(NR_PLAN.selection),
        seed=config["seed"],
        n_shards=NR["n_shards"],
    log:
        "results/logs/nr/q_band.log",
    benchmark:
        "results/benchmarks/nr/q_band.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_q/q_band.py"


rule nr_q_figure:
    """The calibration cost and the headline tracker's error against q, the band shaded."""
    input:
        "results/nr/q_band/q_band.nc",
    output:
        pdf=report(
            "results/figures/nr_q_band.pdf",
            caption="../report/nr_q_band.rst",
            category="nr",
        ),
        png="results/figures/nr_q_band.png",
    log:
        "results/logs/nr/q_figure.log",
    benchmark:
        "results/benchmarks/nr/q_figure.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_q/figure.py"
