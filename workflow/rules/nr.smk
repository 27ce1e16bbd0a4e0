# Study `nr`: 5G NR SS-burst positioning of a high-speed train (source 000, docs/model/nr.md).
# Chain: trajectory -> per-shard channel + burst + per-cell estimates (NetCDF) ->
# calibration run (noise levels, q) -> EKF tracking per realization -> figures + numbers.
from railradio.nr.study import records as nr_records
from railradio.nr.study.plan import nr_plan, plain

# The config's nr section (validated with every cross-key rule in common.smk:
# railradio.config_checks), and what the nr rule files derive from it, computed once and
# read-only (railradio.nr.study.plan.NrPlan): the sensitivity cases and the map's cells are the
# ones the config check merged and validated. A rule's params get plain dicts and lists
# (plain): Snakemake compares their repr to decide re-runs.
NR = config["nr"]
NR_PLAN = nr_plan(
    NR,
    CONFIG_SCHEMA["properties"]["nr"],
    cases=CONFIG_CHECKED.nr_cases,
    map_cells=CONFIG_CHECKED.nr_map_cells,
)

register_figures(
    "nr",
    [
        "nr_trajectory",
        "nr_burst_correlation",
        "nr_measurement_error_cdf",
        "nr_position_error_cdf",
        "nr_position_error_vs_time",
    ],
)
KEY_NUMBER_FRAGMENTS.append("results/nr/key_numbers.json")
if NR_PLAN.cases:
    register_figures("nr_sensitivity", ["nr_sensitivity"] + (["nr_sweeps"] if NR_PLAN.sweeps else []))
    # the cases' paper-scale key numbers are a published record (make records;
    # railradio.published), read while current, else the cases run here: CI's reproduction
    # skips their ~2 000 s of job time; at CI scale (another config) they always run
    KEY_NUMBER_FRAGMENTS.append(nr_records.CASES.fragment(REPO_ROOT, config, "results/nr/cases/key_numbers.json"))


wildcard_constraints:
    real=r"r\d+",
    shard=r"\d+",
    case=r"[a-z][a-z0-9_]*",


rule nr_trajectory:
    """The train's truth: position, speed, acceleration every dt (source Fig. 3)."""
    output:
        "results/nr/trajectory.nc",
    params:
        sim=plain(NR_PLAN.sim),
        n_epochs=NR_PLAN.n_epochs,
    log:
        "results/logs/nr/trajectory.log",
    benchmark:
        "results/benchmarks/nr/trajectory.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/trajectory.py"


rule nr_shard:
    """Channel, received SS bursts and per-cell AOD/TOA estimates of one track shard."""
    output:
        "results/nr/estimates/{real}/s{shard}.nc",
    params:
        real="{real}",
        sim=plain(NR_PLAN.sim),
        seed=config["seed"],
        n_epochs=NR_PLAN.n_epochs,
        n_shards=NR["n_shards"],
    log:
        "results/logs/nr/shard_{real}_s{shard}.log",
    benchmark:
        "results/benchmarks/nr/shard_{real}_s{shard}.tsv"
    wildcard_constraints:
        real=r"r\d+",
    # before the tracks (which Snakemake's greedy scheduler would otherwise start first:
    # they have the larger inputs): the long jobs first, the short ones fill the tail
    priority: 1
    resources:
        mem_mb=3000,
        runtime=60,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/shard.py"


rule nr_cal_shard:
    """A shard of the calibration run (its own trajectory, nr.calibration.trajectory, and
    its own random key); scheduled first so that the calibration overlaps the evaluation
    shards."""
    output:
        "results/nr/estimates/cal/s{shard}.nc",
    params:
        real="cal",
        sim=plain(NR_PLAN.sim),
        seed=config["seed"],
        n_epochs=NR["calibration"]["epochs"],
        n_shards=NR_PLAN.n_cal_shards,
        calibration=NR["calibration"],
    log:
        "results/logs/nr/shard_cal_s{shard}.log",
    benchmark:
        "results/benchmarks/nr/shard_cal_s{shard}.tsv"
    priority: 10
    resources:
        mem_mb=3000,
        runtime=60,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/shard.py"


rule nr_calibrate:
    """Measurement noise and process noise from the calibration run (its own seed key)."""
    input:
        expand("results/nr/estimates/cal/s{shard}.nc", shard=range(NR_PLAN.n_cal_shards)),
    output:
        "results/nr/calibration.json",
    params:
        sim=plain(NR_PLAN.sim),
        tracker=NR["tracker"],
        selection=plain(NR_PLAN.selection),
        measurement_sets=plain(NR_PLAN.measurement_sets),
    log:
        "results/logs/nr/calibrate.log",
    priority: 10
    benchmark:
        "results/benchmarks/nr/calibrate.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/calibrate.py"


rule nr_track:
    """EKF tracks (AOD, TOA, AOD+TOA; gate off/on) and snapshot fixes of one realization."""
    input:
        shards=expand("results/nr/estimates/{{real}}/s{shard}.nc", shard=range(NR["n_shards"])),
        calibration="results/nr/calibration.json",
    output:
        "results/nr/track/{real}.nc",
    params:
        sim=plain(NR_PLAN.sim),
        tracker=NR["tracker"],
        selection=plain(NR_PLAN.selection),
        measurement_sets=plain(NR_PLAN.measurement_sets),
    log:
        "results/logs/nr/track_{real}.log",
    benchmark:
        "results/benchmarks/nr/track_{real}.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/track.py"


rule nr_bounds:
    """Physical limits along the track: TOA CRB, snapshot PEB, tracker PCRB (docs/model/nr.md §7)."""
    input:
        calibration="results/nr/calibration.json",
    output:
        "results/nr/bounds/{real}.nc",
    params:
        sim=plain(NR_PLAN.sim),
        seed=config["seed"],
        n_epochs=NR_PLAN.n_epochs,
        # the calibration of the tracker the IMM study uses (nr.imm.receiver, AOD+TOA, gated)
        calibrated=f"{NR['imm']['receiver']}/aod_toa/gate",
    log:
        "results/logs/nr/bounds_{real}.log",
    benchmark:
        "results/benchmarks/nr/bounds_{real}.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/bounds.py"


rule nr_sample:
    """Raw received IQ and per-block correlations of a few epochs (inspection, figure)."""
    output:
        "results/nr/samples.nc",
    params:
        sim=plain(NR_PLAN.sim),
        seed=config["seed"],
        epochs=[min(2000, NR_PLAN.n_epochs - 1)],
    log:
        "results/logs/nr/sample.log",
    benchmark:
        "results/benchmarks/nr/sample.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/sample.py"


rule nr_figures:
    """All nr figures (cheap: reads the intermediates)."""
    input:
        trajectory="results/nr/trajectory.nc",
        samples="results/nr/samples.nc",
        tracks=expand("results/nr/track/{real}.nc", real=NR_PLAN.realizations),
        bounds=expand("results/nr/bounds/{real}.nc", real=NR_PLAN.realizations),
    output:
        [report(f, caption="../report/nr.rst", category="nr") for f in STUDY_FIGURES["nr"]],
    log:
        "results/logs/nr/figures.log",
    benchmark:
        "results/benchmarks/nr/figures.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/figures.py"


rule nr_key_numbers:
    """Key numbers nr.* pooled over the realizations, with their spread, and the
    calibrated W and q of every tracker."""
    input:
        tracks=expand("results/nr/track/{real}.nc", real=NR_PLAN.realizations),
        bounds=expand("results/nr/bounds/{real}.nc", real=NR_PLAN.realizations),
        calibration="results/nr/calibration.json",
    output:
        "results/nr/key_numbers.json",
    log:
        "results/logs/nr/key_numbers.log",
    benchmark:
        "results/benchmarks/nr/key_numbers.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/key_numbers.py"


# ---- sensitivity cases (docs/model/nr.md §9; paired with realization r0 on the first epochs) ----


rule nr_case_shard:
    """One shard of a sensitivity case: realization r0's bursts under the case's config."""
    output:
        "results/nr/cases/{case}/estimates/{real}/s{shard}.nc",
    params:
        real="{real}",
        sim=lambda w: plain(NR_PLAN.case_sim[w.case]),
        seed=config["seed"],
        n_epochs=lambda w: NR_PLAN.case_n_cal_epochs[w.case] if w.real == "cal" else NR_PLAN.case_n_epochs[w.case],
        n_shards=lambda w: NR_PLAN.case_n_shards[w.case][w.real],
        calibration=lambda w: plain(NR_PLAN.cases[w.case]["calibration"]) if w.real == "cal" else None,
    log:
        "results/logs/nr/cases/{case}_shard_{real}_s{shard}.log",
    benchmark:
        "results/benchmarks/nr/cases/{case}_shard_{real}_s{shard}.tsv"
    wildcard_constraints:
        real="r0|cal",
    resources:
        mem_mb=3000,
        runtime=60,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/shard.py"


rule nr_case_calibrate:
    """Calibration of a sensitivity case (its own calibration run, the main run's key; the
    case's clock errors, nr.sync, on the calibration run's own RRH offsets)."""
    input:
        lambda w: plain(NR_PLAN.case_inputs[w.case]["cal"]),
    output:
        "results/nr/cases/{case}/calibration.json",
    params:
        sim=lambda w: plain(NR_PLAN.case_sim[w.case]),
        tracker=lambda w: plain(NR_PLAN.cases[w.case]["tracker"]),
        selection=lambda w: plain(NR_PLAN.case_selection[w.case]),
        measurement_sets=NR["sensitivity"]["measurement_sets"],
        sync=lambda w: plain(NR_PLAN.cases[w.case]["sync"]),
        seed=config["seed"],
        n_epochs=lambda w: NR_PLAN.case_n_cal_epochs[w.case],
    log:
        "results/logs/nr/cases/{case}_calibrate.log",
    benchmark:
        "results/benchmarks/nr/cases/{case}_calibrate.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/case_calibrate.py"


rule nr_case_track:
    """EKF tracks of a sensitivity case (its epochs; TOAs with the case's clock errors)."""
    input:
        shards=lambda w: plain(NR_PLAN.case_inputs[w.case]["r0"]),
        calibration="results/nr/cases/{case}/calibration.json",
    output:
        "results/nr/cases/{case}/track.nc",
    params:
        sim=lambda w: plain(NR_PLAN.case_sim[w.case]),
        tracker=lambda w: plain(NR_PLAN.cases[w.case]["tracker"]),
        selection=lambda w: plain(NR_PLAN.case_selection[w.case]),
        measurement_sets=NR["sensitivity"]["measurement_sets"],
        sync=lambda w: plain(NR_PLAN.cases[w.case]["sync"]),
        seed=config["seed"],
        n_epochs=lambda w: NR_PLAN.case_n_epochs[w.case],
    log:
        "results/logs/nr/cases/{case}_track.log",
    benchmark:
        "results/benchmarks/nr/cases/{case}_track.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/case_track.py"


rule nr_case_key_numbers:
    """Key numbers sens.nr.<case>.* beside the main run's r0 on the same epochs (base)."""
    input:
        base="results/nr/track/r0.nc",
        cases=expand("results/nr/cases/{case}/track.nc", case=list(NR_PLAN.cases)),
    output:
        "results/nr/cases/key_numbers.json",
    params:
        cases=list(NR_PLAN.cases),
        n_epochs={"base": NR_PLAN.sens_base_epochs} | plain(NR_PLAN.case_n_epochs),
        # the TOA floor of the base and of every case with RRH clock offsets
        sync_sigma_s={"base": 0.0} | {c: s for c, s in NR_PLAN.case_sync_sigma_s.items() if s > 0},
    log:
        "results/logs/nr/cases/key_numbers.log",
    benchmark:
        "results/benchmarks/nr/cases/key_numbers.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/case_key_numbers.py"


rule nr_case_figure:
    """Sensitivity cases beside the base run (measurement and tracking errors)."""
    input:
        numbers="results/nr/cases/key_numbers.json",
    output:
        pdf=report(
            "results/figures/nr_sensitivity.pdf",
            caption="../report/nr_sensitivity.rst",
            category="nr",
        ),
        png="results/figures/nr_sensitivity.png",
    params:
        cases=["base"] + plain(NR_PLAN.unswept_cases),
    log:
        "results/logs/nr/cases/figure.log",
    benchmark:
        "results/benchmarks/nr/cases/figure.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/case_figure.py"


rule nr_case_sweeps_figure:
    """The sensitivity sweeps (speed, RRH spacing, Tx power, clock sync, TDL profile, SS
    beams): one column per sweep, with the integer-sample TOA floor."""
    input:
        numbers="results/nr/cases/key_numbers.json",
    output:
        pdf=report(
            "results/figures/nr_sweeps.pdf",
            caption="../report/nr_sweeps.rst",
            category="nr",
        ),
        png="results/figures/nr_sweeps.png",
    params:
        sweeps=plain(NR_PLAN.sweeps),
        sync_sigma_s=plain(NR_PLAN.case_sync_sigma_s),
    log:
        "results/logs/nr/cases/sweeps_figure.log",
    benchmark:
        "results/benchmarks/nr/cases/sweeps_figure.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/case_sweeps_figure.py"
