# The reproduction map of the nr study (railradio.nr.study.reproduction_map): the source's claims
# for its receiver and ours against the assumptions it leaves open (M_T x data beams, and
# template x selection on the default bursts), and the source receiver's conditions (search
# window x gate x data, railradio.nr.study.conditions), every cell on the same segment of r0 with
# its own short calibration run. Bursts are re-used wherever only the tracker changes, and
# synthesized once per epoch for the cells that differ only in amplitudes or receivers.
# The cells, their runs and the shards they read: NR_PLAN.map_* (nr.smk; railradio.nr.study.plan).
from railradio.nr.engine.variants import variant_groups
from railradio.nr.study import records as nr_records

register_figures("nr_map", ["nr_reproduction_map", "nr_conditions"])
# Its paper-scale key numbers are a published record (make records; railradio.published): the
# merge reads the record while it is current (the map's code and config unchanged since it
# was published), else the map runs here. CI's reproduction thus skips the map, whose
# 1 000-epoch segments of 19 cells are about a third of the paper scale's job time; at CI
# scale (another config) the map always runs.
KEY_NUMBER_FRAGMENTS.append(nr_records.MAP.fragment(REPO_ROOT, config, "results/nr/map/key_numbers.json"))


# The cells owning each run's bursts (the others read another cell's or the main run's). The
# owners differing only in amplitudes (M_T, the data's beam and load) or receivers share one
# synthesis per epoch (railradio.nr.engine.variants.simulate_cells): one job per run and shard
# makes all their estimate shards. An owner in no such group (the sanity row, another range)
# has its own jobs, so that adding or changing it leaves the shared shards as they are.
# "_none": no owner, a path nothing asks for.
_OWNERS = {
    real: [
        c
        for c in NR_PLAN.map_cells
        if any(f"results/nr/map/{c}/estimates/{real}/" in p for i in NR_PLAN.map_inputs.values() for p in i[real])
    ]
    for real in ("r0", "cal")
}
_SHARED = {
    real: {c for g in variant_groups({c: NR_PLAN.map_burst_config[c] for c in owners}) for c in g}
    for real, owners in _OWNERS.items()
}
MAP_OWNERS = {real: [c for c in owners if c in _SHARED[real]] or ["_none"] for real, owners in _OWNERS.items()}
# per run: a cell may share one run's synthesis and not the other's (the default cell owns
# only its calibration run), so each run's solo cells have their own rule
MAP_SOLO = {real: [c for c in owners if c not in _SHARED[real]] for real, owners in _OWNERS.items()}


rule nr_map_segment_shard:
    """A shard of the segment (r0's key) for every cell owning its bursts."""
    output:
        expand("results/nr/map/{cell}/estimates/r0/s{{shard}}.nc", cell=MAP_OWNERS["r0"]),
    params:
        sims=[plain(NR_PLAN.map_burst_config[c]) for c in MAP_OWNERS["r0"] if c in NR_PLAN.map_cells],
        cells=MAP_OWNERS["r0"],
        real="r0",
        seed=config["seed"],
        epochs=plain(NR_PLAN.map_epochs["r0"]),
        n_shards=NR_PLAN.map_n_shards["r0"],
        calibration=None,
        rid=NR_PLAN.map_rid["r0"],
    log:
        "results/logs/nr/map/segment_s{shard}.log",
    benchmark:
        "results/benchmarks/nr/map/segment_s{shard}.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_map/shard.py"


rule nr_map_calibration_shard:
    """The cells' short calibration run (its own trajectory at speed and key) for every cell
    owning its bursts."""
    output:
        expand("results/nr/map/{cell}/estimates/cal/s{{shard}}.nc", cell=MAP_OWNERS["cal"]),
    params:
        sims=[plain(NR_PLAN.map_burst_config[c]) for c in MAP_OWNERS["cal"] if c in NR_PLAN.map_cells],
        cells=MAP_OWNERS["cal"],
        real="cal",
        seed=config["seed"],
        epochs=plain(NR_PLAN.map_epochs["cal"]),
        n_shards=NR_PLAN.map_n_shards["cal"],
        calibration=plain(NR_PLAN.map_calibration),
        rid=NR_PLAN.map_rid["cal"],
    log:
        "results/logs/nr/map/calibration_s{shard}.log",
    benchmark:
        "results/benchmarks/nr/map/calibration_s{shard}.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_map/shard.py"


rule nr_map_solo_segment_shard:
    """A shard of the segment (r0's key) of a cell owning bursts no other cell shares
    (MAP_SOLO["r0"])."""
    output:
        "results/nr/map/{cell}/estimates/r0/s{shard}.nc",
    params:
        sims=lambda w: [plain(NR_PLAN.map_burst_config[w.cell])],
        cells=lambda w: [w.cell],
        real="r0",
        seed=config["seed"],
        epochs=plain(NR_PLAN.map_epochs["r0"]),
        n_shards=NR_PLAN.map_n_shards["r0"],
        calibration=None,
        rid=NR_PLAN.map_rid["r0"],
    wildcard_constraints:
        cell="|".join(MAP_SOLO["r0"]) or "_none",
        shard=r"\d+",
    log:
        "results/logs/nr/map/{cell}_r0_s{shard}.log",
    benchmark:
        "results/benchmarks/nr/map/{cell}_r0_s{shard}.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_map/shard.py"


rule nr_map_solo_calibration_shard:
    """The short calibration run of a cell owning bursts no other cell shares
    (MAP_SOLO["cal"])."""
    output:
        "results/nr/map/{cell}/estimates/cal/s{shard}.nc",
    params:
        sims=lambda w: [plain(NR_PLAN.map_burst_config[w.cell])],
        cells=lambda w: [w.cell],
        real="cal",
        seed=config["seed"],
        epochs=plain(NR_PLAN.map_epochs["cal"]),
        n_shards=NR_PLAN.map_n_shards["cal"],
        calibration=plain(NR_PLAN.map_calibration),
        rid=NR_PLAN.map_rid["cal"],
    wildcard_constraints:
        cell="|".join(MAP_SOLO["cal"]) or "_none",
        shard=r"\d+",
    log:
        "results/logs/nr/map/{cell}_cal_s{shard}.log",
    benchmark:
        "results/benchmarks/nr/map/{cell}_cal_s{shard}.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_map/shard.py"


rule nr_map_cell:
    """A map cell's trackers: each receiver's AOD, TOA and AOD+TOA EKF (the source's
    ungated, ours gated) calibrated on the cell's calibration run, run on the segment."""
    input:
        segment=lambda w: plain(NR_PLAN.map_inputs[w.cell]["r0"]),
        calibration=lambda w: plain(NR_PLAN.map_inputs[w.cell]["cal"]),
    output:
        "results/nr/map/{cell}/track.nc",
    params:
        sim=lambda w: plain(NR_PLAN.map_burst_config[w.cell]),
        tracker=NR["tracker"],
        selection=lambda w: plain(NR_PLAN.map_selection[w.cell]),
        receivers=lambda w: plain(NR_PLAN.map_receivers[w.cell]),
        segment=plain(NR_PLAN.map_segment),
        start_speed_sigma_m_s=NR["map"]["start_speed_sigma_m_s"],
    wildcard_constraints:
        cell=r"[a-z][a-z0-9_]*",
    log:
        "results/logs/nr/map/{cell}_track.log",
    benchmark:
        "results/benchmarks/nr/map/{cell}_track.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_map/cell.py"


rule nr_map_key_numbers:
    """Key numbers nr.map.<cell>.<receiver>.<metric> with block-bootstrap intervals, the
    claims' statuses, and per claim the cells where it holds / fails / is not resolved."""
    input:
        expand("results/nr/map/{cell}/track.nc", cell=list(NR_PLAN.map_cells)),
    output:
        "results/nr/map/key_numbers.json",
    params:
        cells=list(NR_PLAN.map_cells),
        seed=config["seed"],
        map=NR["map"],
        nr=NR,
    log:
        "results/logs/nr/map/key_numbers.log",
    benchmark:
        "results/benchmarks/nr/map/key_numbers.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_map/key_numbers.py"


rule nr_map_figure:
    """The reproduction map: one grid per receiver, a cell per assumption set and claim."""
    input:
        "results/nr/map/key_numbers.json",
    output:
        pdf=report(
            "results/figures/nr_reproduction_map.pdf",
            caption="../report/nr_reproduction_map.rst",
            category="nr",
        ),
        png="results/figures/nr_reproduction_map.png",
    params:
        cells=list(NR_PLAN.map_cells),
        nr=NR,
    log:
        "results/logs/nr/map/figure.log",
    benchmark:
        "results/benchmarks/nr/map/figure.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_map/figure.py"


rule nr_conditions_figure:
    """The source receiver's conditions: each claim's status per window x gate x data, and
    the fewest departures under which it holds."""
    input:
        "results/nr/map/key_numbers.json",
    output:
        pdf=report(
            "results/figures/nr_conditions.pdf",
            caption="../report/nr_conditions.rst",
            category="nr",
        ),
        png="results/figures/nr_conditions.png",
    params:
        nr=NR,
    log:
        "results/logs/nr/map/conditions_figure.log",
    benchmark:
        "results/benchmarks/nr/map/conditions_figure.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_map/conditions_figure.py"
