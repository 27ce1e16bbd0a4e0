# Study `nr`: 5G NR SS-burst positioning of a high-speed train (source 000, docs/model/nr.md).
# Chain: trajectory -> per-shard channel + burst + per-cell estimates (NetCDF) ->
# calibration run (noise levels, q) -> EKF tracking per realization -> figures + numbers.
from railradio.nr.workflow import receiver_selection as nr_selection
from railradio.nr.simulate import scenario_from_config
from railradio.nr.workflow import sim_config as nr_sim
from railradio.nr import cases as nr_cases
from railradio.nr import records as nr_records
from railradio.nr.measurement import MEASUREMENT_SETS

# (validated with every cross-key rule in common.smk: railradio.config_checks)
NR = config["nr"]
NR_SCN = scenario_from_config(NR)
NR_EPOCHS = (
    NR_SCN.trajectory.n_epochs
    if NR["max_epochs"] is None
    else min(NR["max_epochs"], NR_SCN.trajectory.n_epochs)
)
NR_REALS = [f"r{i}" for i in range(NR["realizations"])]
NR_CAL_SHARDS = 2
NR_SIM = nr_sim(NR)
NR_MEASUREMENT_SETS = list(MEASUREMENT_SETS)  # the main run tracks every measurement set (source §4)
NR_SELECTION = nr_selection(NR)

# Sensitivity cases: the nr config with a case's override merged in
NR_SENS = NR["sensitivity"]
NR_CASES = nr_cases.merged_cases(NR, CONFIG_SCHEMA["properties"]["nr"])
NR_CASE_EPOCHS = min(NR_SENS["epochs"], NR_SCN.trajectory.n_epochs)
NR_SWEEPS = NR_SENS["sweeps"]
NR_CASE_N = {c: nr_cases.case_epochs(NR_CASES[c], NR_SENS) for c in NR_CASES}
NR_CASE_N_CAL = {c: nr_cases.case_cal_epochs(NR_CASES[c], NR) for c in NR_CASES}

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
if NR_CASES:
    register_figures("nr_sensitivity", ["nr_sensitivity"] + (["nr_sweeps"] if NR_SWEEPS else []))
    # the cases' paper-scale key numbers are a published record (make records;
    # railradio.published), read while current, else the cases run here: CI's reproduction
    # skips their ~2 000 s of job time; at CI scale (another config) they always run
    KEY_NUMBER_FRAGMENTS.append(
        nr_records.CASES.fragment(Path(workflow.basedir), config, "results/nr/cases/key_numbers.json")
    )


wildcard_constraints:
    real=r"r\d+",
    shard=r"\d+",
    case=r"[a-z][a-z0-9_]*",


rule nr_trajectory:
    """The train's truth: position, speed, acceleration every dt (source Fig. 3)."""
    output:
        "results/nr/trajectory.nc",
    params:
        sim=NR_SIM,
        n_epochs=NR_EPOCHS,
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
        sim=NR_SIM,
        seed=config["seed"],
        n_epochs=NR_EPOCHS,
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
        sim=NR_SIM,
        seed=config["seed"],
        n_epochs=NR["calibration"]["epochs"],
        n_shards=NR_CAL_SHARDS,
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
        expand("results/nr/estimates/cal/s{shard}.nc", shard=range(NR_CAL_SHARDS)),
    output:
        "results/nr/calibration.json",
    params:
        sim=NR_SIM,
        tracker=NR["tracker"],
        selection=NR_SELECTION,
        measurement_sets=NR_MEASUREMENT_SETS,
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
        sim=NR_SIM,
        tracker=NR["tracker"],
        selection=NR_SELECTION,
        measurement_sets=NR_MEASUREMENT_SETS,
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
        sim=NR_SIM,
        seed=config["seed"],
        n_epochs=NR_EPOCHS,
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
        sim=NR_SIM,
        seed=config["seed"],
        epochs=[min(2000, NR_EPOCHS - 1)],
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
        tracks=expand("results/nr/track/{real}.nc", real=NR_REALS),
        bounds=expand("results/nr/bounds/{real}.nc", real=NR_REALS),
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
        tracks=expand("results/nr/track/{real}.nc", real=NR_REALS),
        bounds=expand("results/nr/bounds/{real}.nc", real=NR_REALS),
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
        sim=lambda w: nr_sim(NR_CASES[w.case]),
        seed=config["seed"],
        n_epochs=lambda w: NR_CASE_N_CAL[w.case] if w.real == "cal" else NR_CASE_N[w.case],
        n_shards=lambda w: nr_cases.case_n_shards(NR_CASES[w.case], NR, NR_SENS, w.real, NR_CAL_SHARDS),
        calibration=lambda w: NR_CASES[w.case]["calibration"] if w.real == "cal" else None,
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
        lambda w: nr_cases.case_inputs(w.case, NR_CASES, NR, NR_SENS, "cal", NR_EPOCHS, NR_CAL_SHARDS),
    output:
        "results/nr/cases/{case}/calibration.json",
    params:
        sim=lambda w: nr_sim(NR_CASES[w.case]),
        tracker=lambda w: NR_CASES[w.case]["tracker"],
        selection=lambda w: nr_selection(NR_CASES[w.case]),
        measurement_sets=NR_SENS["measurement_sets"],
        sync=lambda w: NR_CASES[w.case]["sync"],
        seed=config["seed"],
        n_epochs=lambda w: NR_CASE_N_CAL[w.case],
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
        shards=lambda w: nr_cases.case_inputs(w.case, NR_CASES, NR, NR_SENS, "r0", NR_EPOCHS, NR_CAL_SHARDS),
        calibration="results/nr/cases/{case}/calibration.json",
    output:
        "results/nr/cases/{case}/track.nc",
    params:
        sim=lambda w: nr_sim(NR_CASES[w.case]),
        tracker=lambda w: NR_CASES[w.case]["tracker"],
        selection=lambda w: nr_selection(NR_CASES[w.case]),
        measurement_sets=NR_SENS["measurement_sets"],
        sync=lambda w: NR_CASES[w.case]["sync"],
        seed=config["seed"],
        n_epochs=lambda w: NR_CASE_N[w.case],
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
        cases=expand("results/nr/cases/{case}/track.nc", case=list(NR_CASES)),
    output:
        "results/nr/cases/key_numbers.json",
    params:
        cases=list(NR_CASES),
        n_epochs={"base": NR_CASE_EPOCHS} | NR_CASE_N,
        # the TOA floor of the base and of every case with RRH clock offsets
        sync_sigma_s={"base": 0.0} | {c: nr_cases.sync_sigma_s(NR_CASES[c]) for c in NR_CASES
                                      if nr_cases.sync_sigma_s(NR_CASES[c]) > 0},
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
        cases=["base"] + [c for c in NR_CASES if not any(c in sw["cases"] for sw in NR_SWEEPS.values())],
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
        sweeps=NR_SWEEPS,
        sync_sigma_s={c: nr_cases.sync_sigma_s(NR_CASES[c]) for c in NR_CASES},
    log:
        "results/logs/nr/cases/sweeps_figure.log",
    benchmark:
        "results/benchmarks/nr/cases/sweeps_figure.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/case_sweeps_figure.py"
