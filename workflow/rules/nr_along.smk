# Along-track and cross-track errors (docs/model/nr.md §6): every tracker free in 2-D and
# held on the track (y = 0), gated and not, the IMM runs' filters, and the headline tracker's
# along-track protection level. Reads the nr shards, calibration and IMM runs; simulates nothing.

register_figures("nr_along", ["nr_along_track"])
KEY_NUMBER_FRAGMENTS.append("results/nr/along/key_numbers.json")


rule nr_along_track:
    """Every tracker free and track-bound, the IMM's: along/cross-track errors, protection level."""
    input:
        runs=expand("results/nr/estimates/{real}/s{shard}.nc", real=NR_PLAN.realizations, shard=range(NR["n_shards"])),
        calibration="results/nr/calibration.json",
        imm=expand("results/nr/imm/{real}.nc", real=NR_PLAN.realizations),
    output:
        nc="results/nr/along/along_track.nc",
        numbers="results/nr/along/key_numbers.json",
    params:
        sim=plain(NR_PLAN.sim),
        tracker=NR["tracker"],
        selection=plain(NR_PLAN.selection),
        n_shards=NR["n_shards"],
    log:
        "results/logs/nr/along_track.log",
    benchmark:
        "results/benchmarks/nr/along_track.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_along/along_track.py"


rule nr_along_figure:
    """Along/cross-track errors of our receiver's trackers; the headline's protection level."""
    input:
        "results/nr/along/along_track.nc",
    output:
        pdf=report(
            "results/figures/nr_along_track.pdf",
            caption="../report/nr_along_track.rst",
            category="nr",
        ),
        png="results/figures/nr_along_track.png",
    log:
        "results/logs/nr/along_figure.log",
    benchmark:
        "results/benchmarks/nr/along_figure.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_along/figure.py"
