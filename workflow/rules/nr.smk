# Study `nr`: 5G NR SS-burst positioning of a high-speed train (seed 000, STUDY.md §2).
# Chain: trajectory -> per-shard channel + burst + per-cell estimates (NetCDF) ->
# calibration run (noise levels, q) -> EKF tracking per realization -> figures + numbers.
from railradio.nr.simulate import scenario_from_config

NR = config["nr"]
NR_SCN = scenario_from_config(NR)
NR_EPOCHS = (
    NR_SCN.trajectory.n_epochs
    if NR["max_epochs"] is None
    else min(NR["max_epochs"], NR_SCN.trajectory.n_epochs)
)
NR_REALS = [f"r{i}" for i in range(NR["realizations"])]
NR_CAL_SHARDS = 2
NR_SIM_KEYS = ["trajectory", "deployment", "radio", "antenna", "channel", "receiver", "receiver_variants"]
NR_SIM = {k: NR[k] for k in NR_SIM_KEYS if k in NR}
NR_SELECTION = {"seed": NR["receiver"]["selection"]} | {
    name: v["selection"] for name, v in NR.get("receiver_variants", {}).items()
}
CODE_NR_SIM = (
    code_hash(
        "railradio.nr",
        exclude=("figures.py", "keys.py", "tracking.py", "bounds.py"),
        data=("tdl.json",),
    )
    + CODE_SHARED
)
CODE_NR_TRACK = code_hash("railradio.nr.tracking") + CODE_NR_SIM

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


wildcard_constraints:
    real=r"r\d+|cal",
    shard=r"\d+",


rule nr_trajectory:
    """The train's truth: position, speed, acceleration every dt (seed Fig. 3)."""
    output:
        "results/nr/trajectory.nc",
    params:
        sim=NR_SIM,
        n_epochs=NR_EPOCHS,
        code=CODE_NR_SIM,
    log:
        "results/logs/nr/trajectory.log",
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/trajectory.py"


rule nr_shard:
    """Channel, received SS bursts and per-cell AOD/TOA estimates of one track shard."""
    output:
        "results/nr/estimates/{real}/s{shard}.nc",
    params:
        sim=NR_SIM,
        seed=config["seed"],
        n_epochs=lambda w: NR["calibration"]["epochs"] if w.real == "cal" else NR_EPOCHS,
        n_shards=lambda w: NR_CAL_SHARDS if w.real == "cal" else NR["n_shards"],
        code=CODE_NR_SIM,
    log:
        "results/logs/nr/shard_{real}_s{shard}.log",
    benchmark:
        "results/benchmarks/nr/shard_{real}_s{shard}.tsv"
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
        code=CODE_NR_TRACK,
    log:
        "results/logs/nr/calibrate.log",
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
        code=CODE_NR_TRACK,
    log:
        "results/logs/nr/track_{real}.log",
    benchmark:
        "results/benchmarks/nr/track_{real}.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/track.py"


rule nr_bounds:
    """Physical limits along the track: TOA CRB, snapshot PEB, tracker PCRB (STUDY.md §2.7)."""
    input:
        calibration="results/nr/calibration.json",
    output:
        "results/nr/bounds/{real}.nc",
    params:
        sim=NR_SIM,
        seed=config["seed"],
        n_epochs=NR_EPOCHS,
        calibrated=(
            "robust/aod_toa/gate"
            if "robust" in NR.get("receiver_variants", {})
            else "seed/aod_toa/gate"
        ),
        code=code_hash("railradio.nr.bounds", data=("tdl.json",)) + CODE_NR_TRACK,
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
        code=CODE_NR_SIM,
    log:
        "results/logs/nr/sample.log",
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
    params:
        code=code_hash("railradio.nr.figures") + CODE_PLOT,
    log:
        "results/logs/nr/figures.log",
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/figures.py"


rule nr_key_numbers:
    """Key numbers nr.* pooled over the realizations, with their spread."""
    input:
        tracks=expand("results/nr/track/{real}.nc", real=NR_REALS),
        bounds=expand("results/nr/bounds/{real}.nc", real=NR_REALS),
    output:
        "results/nr/key_numbers.json",
    params:
        code=code_hash("railradio.nr.keys", "railradio.keynumbers"),
    log:
        "results/logs/nr/key_numbers.log",
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr/key_numbers.py"
