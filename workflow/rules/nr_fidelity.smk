# The nr study's shortcuts measured where they run (railradio.nr.study.fidelity): on paper-scale
# epochs of one realization of the main run, the production path against the same path with
# one shortcut replaced by the exact computation, and against the exact computation. Outside
# `all` (the exact reference costs ~14 s an epoch): target `fidelity`; `make fidelity`
# publishes its key numbers to paper/fidelity_numbers.json, which the key-number merge reads.
from railradio.nr.study import records as nr_records

# the published paper-scale numbers (make fidelity) join every run's key numbers
if (REPO_ROOT / nr_records.FIDELITY.numbers_file).exists():
    KEY_NUMBER_FRAGMENTS.append(nr_records.FIDELITY.numbers_file)


rule nr_fidelity_shard:
    """Every path on one shard of the sampled epochs (the main run's candidate lists and
    serving cells there)."""
    input:
        expand("results/nr/estimates/{real}/s{shard}.nc", real=NR_PLAN.fidelity_real, shard=range(NR["n_shards"])),
    output:
        "results/nr/fidelity/s{fshard}.nc",
    params:
        sim=plain(NR_PLAN.sim),
        seed=config["seed"],
        n_epochs=NR_PLAN.n_epochs,
        fidelity=NR["fidelity"],
        selection=plain(NR_PLAN.selection),
    wildcard_constraints:
        fshard=r"\d+",
    log:
        "results/logs/nr/fidelity_s{fshard}.log",
    benchmark:
        "results/benchmarks/nr/fidelity_s{fshard}.tsv"
    resources:
        mem_mb=3000,
        runtime=120,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_fidelity/shard.py"


rule nr_fidelity:
    """Key numbers nr.fidelity.* and nr.detector.*, and the figure of the changed decisions."""
    input:
        expand("results/nr/fidelity/s{fshard}.nc", fshard=range(NR["fidelity"]["n_shards"])),
    output:
        json="results/nr/fidelity/key_numbers.json",
        pdf="results/nr/fidelity/nr_fidelity.pdf",
        png="results/nr/fidelity/nr_fidelity.png",
    params:
        sim=plain(NR_PLAN.sim),
        seed=config["seed"],
        noise_bursts=NR["fidelity"]["noise_bursts"],
    log:
        "results/logs/nr/fidelity.log",
    benchmark:
        "results/benchmarks/nr/fidelity.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_fidelity/key_numbers.py"
