# The reproduction map of the nr study (railradio.nr.reproduction_map): the source's claims
# for its receiver and ours against the assumptions it leaves open (M_T x data beams, and
# template x selection on the default bursts), every cell on the same segment of r0 with
# its own short calibration run. Bursts are re-used wherever only the tracker changes.
from railradio.nr import records as nr_records
from railradio.nr import reproduction_map as nr_map

NR_MAP = NR["map"]
NR_MAP_CELLS = nr_map.cells(NR, CONFIG_SCHEMA["properties"]["nr"])
NR_MAP_SEGMENT = [int(e) for e in NR_MAP["segment"]]
NR_MAP_CALIBRATION = nr_map.calibration_section(NR)
NR_MAP_RID = {"r0": 0, "cal": 1001}  # the segment is r0's; the calibration runs have their own key

register_figures("nr_map", ["nr_reproduction_map"])
# Its paper-scale key numbers are a published record (make records; railradio.published): the
# merge reads the record while it is current (the map's code and config unchanged since it
# was published), else the map runs here. CI's reproduction thus skips the map, whose
# 1 000-epoch segments of 19 cells are about a third of the paper scale's job time; at CI
# scale (another config) the map always runs.
KEY_NUMBER_FRAGMENTS.append(nr_records.MAP.fragment(Path(workflow.basedir), config, "results/nr/map/key_numbers.json"))


rule nr_map_shard:
    """A map cell's bursts and estimates: a shard of the segment (r0's key) or its short
    calibration run (its own trajectory at speed and key)."""
    output:
        "results/nr/map/{cell}/estimates/{real}/s{shard}.nc",
    params:
        sim=lambda w: nr_map.burst_config(NR_MAP_CELLS[w.cell]),
        seed=config["seed"],
        epochs=lambda w: NR_MAP_SEGMENT if w.real == "r0" else [0, NR_MAP_CALIBRATION["epochs"]],
        n_shards=lambda w: NR_MAP["n_shards"] if w.real == "r0" else 1,
        calibration=lambda w: NR_MAP_CALIBRATION if w.real == "cal" else None,
        rid=lambda w: NR_MAP_RID[w.real],
    wildcard_constraints:
        cell=r"[a-z][a-z0-9_]*",
        real="r0|cal",
    log:
        "results/logs/nr/map/{cell}_shard_{real}_s{shard}.log",
    benchmark:
        "results/benchmarks/nr/map/{cell}_shard_{real}_s{shard}.tsv"
    resources:
        mem_mb=3000,
        runtime=60,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_map/shard.py"


rule nr_map_cell:
    """A map cell's trackers: each receiver's AOD, TOA and AOD+TOA EKF (the source's
    ungated, ours gated) calibrated on the cell's calibration run, run on the segment."""
    input:
        segment=lambda w: nr_map.shard_paths(w.cell, "r0", NR_MAP_CELLS, NR, NR_EPOCHS),
        calibration=lambda w: nr_map.shard_paths(w.cell, "cal", NR_MAP_CELLS, NR, NR_EPOCHS),
    output:
        "results/nr/map/{cell}/track.nc",
    params:
        sim=lambda w: nr_map.burst_config(NR_MAP_CELLS[w.cell]),
        tracker=NR["tracker"],
        selection=lambda w: nr_selection(NR_MAP_CELLS[w.cell]),
        receivers=lambda w: {rx: g for rx, g in nr_map.receivers(NR).items()
                             if rx in nr_map.cell_receivers(w.cell, NR)},
        segment=NR_MAP_SEGMENT,
        start_speed_sigma_m_s=NR_MAP["start_speed_sigma_m_s"],
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
        expand("results/nr/map/{cell}/track.nc", cell=list(NR_MAP_CELLS)),
    output:
        "results/nr/map/key_numbers.json",
    params:
        cells=list(NR_MAP_CELLS),
        seed=config["seed"],
        map=NR_MAP,
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
        cells=list(NR_MAP_CELLS),
        nr=NR,
    log:
        "results/logs/nr/map/figure.log",
    benchmark:
        "results/benchmarks/nr/map/figure.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/nr_map/figure.py"
