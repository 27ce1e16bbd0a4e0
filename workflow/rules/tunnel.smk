# Study `tunnel`: long-train positioning with a leaky cable in a tunnel (source 003; docs/model/tunnel.md).
# Chain: ray families -> tabulated slot-to-receiver channel per engine (NetCDF) ->
# RSSI map, delay spread, coverage (NetCDF) -> one run per train type and channel /
# measurement setup (snapshot fixes, KF, PF; NetCDF) -> figures + key numbers.
from railradio.tunnel.sensitivity import sensitivity_cases
from railradio.tunnel.study import SETUPS, SIDE_WALL, TABLES, channel_config

TUNNEL = config["tunnel"]
TUNNEL_TABLES = [n for n in TABLES if SIDE_WALL not in n]  # image (square), source (the source's model)
TUNNEL_SIDE_WALL = TUNNEL["engine"] + SIDE_WALL  # the engine's channel with the cable on the side wall
TUNNEL_TRAINS = list(TUNNEL["trains"])
TUNNEL_SETUPS = list(SETUPS)
TUNNEL_RUNS = [f"{t}/{s}" for t in TUNNEL_TRAINS for s in TUNNEL_SETUPS]
TUNNEL_CHANNEL_KEYS = ["geometry", "cable", "wall", "rays", "source_model"]
TUNNEL_CHANNEL = {k: TUNNEL[k] for k in TUNNEL_CHANNEL_KEYS}
TUNNEL_FIGURE_NAMES = [
    "tunnel_rssi_map",
    "tunnel_delay_spread",
    "tunnel_gdop",
    "tunnel_position_error_cdf",
    "tunnel_ray_engines",
    "tunnel_source_vs_physical",
]

register_figures("tunnel", TUNNEL_FIGURE_NAMES + ["tunnel_sensitivity"])
KEY_NUMBER_FRAGMENTS.append("results/tunnel/key_numbers.json")


rule tunnel_order:
    """Reflection order by convergence of the coherent gain (image method), per cable
    placement: the centreline and the side wall."""
    output:
        "results/tunnel/order_{placement}.nc",
    params:
        cfg=lambda w: channel_config(
            TUNNEL, "image" + (SIDE_WALL if w.placement == "side_wall" else ""), TUNNEL_CHANNEL_KEYS
        ),
    wildcard_constraints:
        placement="centreline|side_wall",
    log:
        "results/logs/tunnel/order_{placement}.log",
    benchmark:
        "results/benchmarks/tunnel/order_{placement}.tsv"
    resources:
        mem_mb=3000,
        runtime=10,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/tunnel/order.py"


rule tunnel_table:
    """Ray families of one engine, tabulated by slot-receiver offset at the placement's order."""
    input:
        lambda w: "results/tunnel/order_{}.nc".format("side_wall" if SIDE_WALL in w.name else "centreline"),
    output:
        "results/tunnel/table_{name}.nc",
    params:
        cfg=lambda w: channel_config(TUNNEL, w.name, TUNNEL_CHANNEL_KEYS),
        seed=config["seed"],
    wildcard_constraints:
        name="|".join(TABLES),
    log:
        "results/logs/tunnel/table_{name}.log",
    benchmark:
        "results/benchmarks/tunnel/table_{name}.tsv"
    resources:
        mem_mb=3000,
        runtime=10,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/tunnel/table.py"


rule tunnel_map:
    """RSSI (coherent, local mean), RMS delay spread and usable rays along the tunnel."""
    input:
        "results/tunnel/table_{name}.nc",
    output:
        "results/tunnel/map_{name}.nc",
    params:
        cfg=lambda w: channel_config(TUNNEL, w.name, TUNNEL_CHANNEL_KEYS) | {"coverage": TUNNEL["coverage"]},
    wildcard_constraints:
        name="|".join(TABLES),
    log:
        "results/logs/tunnel/map_{name}.log",
    benchmark:
        "results/benchmarks/tunnel/map_{name}.tsv"
    resources:
        mem_mb=3000,
        runtime=10,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/tunnel/map.py"


rule tunnel_engines:
    """Image method vs SBR in the square tunnel (and SBR in the circle) at fixed offsets; the
    far-decay checks and the image-method table's cut-off check."""
    input:
        "results/tunnel/table_image.nc",
    output:
        "results/tunnel/engines.nc",
    params:
        cfg=TUNNEL_CHANNEL,
    log:
        "results/logs/tunnel/engines.log",
    benchmark:
        "results/benchmarks/tunnel/engines.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/tunnel/engines.py"


rule tunnel_run:
    """One train type crossing the tunnel: measurements, snapshot fixes, KF, rigid KF, PF."""
    input:
        lambda w: "results/tunnel/table_{}.nc".format("source" if SETUPS[w.setup][0] == "source" else TUNNEL["engine"]),
    output:
        "results/tunnel/runs/{train}/{setup}.nc",
    params:
        cfg=lambda w: TUNNEL_CHANNEL
        | {k: TUNNEL[k] for k in ("measurement", "trains", "positioning", "tracking", "realizations", "cases")},
        seed=config["seed"],
    wildcard_constraints:
        train="metro|hst|freight",
        setup="|".join(SETUPS),
    log:
        "results/logs/tunnel/run_{train}_{setup}.log",
    benchmark:
        "results/benchmarks/tunnel/run_{train}_{setup}.tsv"
    resources:
        mem_mb=3000,
        runtime=20,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/tunnel/run.py"


rule tunnel_sensitivity:
    """One train type through the sensitivity cases (shadowing and delay-error sigma swept
    over the source's ranges, delay-error models), R realizations each, KF only."""
    input:
        table=lambda w: "results/tunnel/table_{}.nc".format(TUNNEL["engine"]),
        side_wall=f"results/tunnel/table_{TUNNEL_SIDE_WALL}.nc",
    output:
        "results/tunnel/sens/{train}.nc",
    params:
        cfg=TUNNEL_CHANNEL
        | {k: TUNNEL[k] for k in ("measurement", "trains", "positioning", "tracking", "realizations", "sensitivity")},
        seed=config["seed"],
    wildcard_constraints:
        train="metro|hst|freight",
    log:
        "results/logs/tunnel/sens_{train}.log",
    benchmark:
        "results/benchmarks/tunnel/sens_{train}.tsv"
    resources:
        mem_mb=3000,
        runtime=20,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/tunnel/sensitivity.py"


rule tunnel_peak_bias:
    """Where the wideband peak-delay bias comes from: noiseless CIR peak minus the cable-point
    model along the tunnel, one slot / all slots' line of sight / full channel."""
    input:
        lambda w: "results/tunnel/table_{}.nc".format(TUNNEL["engine"]),
    output:
        "results/tunnel/peak_bias.nc",
    params:
        cfg=TUNNEL_CHANNEL | {"measurement": TUNNEL["measurement"]},
    log:
        "results/logs/tunnel/peak_bias.log",
    benchmark:
        "results/benchmarks/tunnel/peak_bias.tsv"
    resources:
        mem_mb=3000,
        runtime=10,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/tunnel/peak_bias.py"


rule tunnel_figures:
    """The six tunnel figures (cheap: reads the intermediates)."""
    input:
        maps=expand("results/tunnel/map_{name}.nc", name=TUNNEL_TABLES),
        tables=expand("results/tunnel/table_{name}.nc", name=TUNNEL_TABLES),
        runs=expand("results/tunnel/runs/{run}.nc", run=TUNNEL_RUNS),
        engines="results/tunnel/engines.nc",
    output:
        [
            report(f, caption="../report/tunnel.rst", category="tunnel")
            for f in STUDY_FIGURES["tunnel"]
            if "tunnel_sensitivity" not in f
        ],
    params:
        cfg=TUNNEL,
        tables=TUNNEL_TABLES,
        runs=TUNNEL_RUNS,
        names=TUNNEL_FIGURE_NAMES,
    log:
        "results/logs/tunnel/figures.log",
    benchmark:
        "results/benchmarks/tunnel/figures.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/tunnel/figures.py"


rule tunnel_sens_figure:
    """95th-percentile error against the shadowing and the delay-error sigma, per delay-error model."""
    input:
        expand("results/tunnel/sens/{train}.nc", train=TUNNEL_TRAINS),
    output:
        pdf=report(
            "results/figures/tunnel_sensitivity.pdf",
            caption="../report/tunnel_sensitivity.rst",
            category="tunnel",
        ),
        png="results/figures/tunnel_sensitivity.png",
    params:
        sensitivity=TUNNEL["sensitivity"],
        trains=TUNNEL_TRAINS,
    log:
        "results/logs/tunnel/sens_figure.log",
    benchmark:
        "results/benchmarks/tunnel/sens_figure.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/tunnel/sens_figure.py"


rule tunnel_key_numbers:
    """Key numbers tunnel.* beside the source's design targets."""
    input:
        maps=expand("results/tunnel/map_{name}.nc", name=TUNNEL_TABLES),
        tables=expand("results/tunnel/table_{name}.nc", name=TUNNEL_TABLES),
        runs=expand("results/tunnel/runs/{run}.nc", run=TUNNEL_RUNS),
        engines="results/tunnel/engines.nc",
        sens=expand("results/tunnel/sens/{train}.nc", train=TUNNEL_TRAINS),
        peak_bias="results/tunnel/peak_bias.nc",
        side_wall_map=f"results/tunnel/map_{TUNNEL_SIDE_WALL}.nc",
    output:
        "results/tunnel/key_numbers.json",
    params:
        cfg=TUNNEL,
        tables=TUNNEL_TABLES,
        runs=TUNNEL_RUNS,
        trains=TUNNEL_TRAINS,
    log:
        "results/logs/tunnel/key_numbers.log",
    benchmark:
        "results/benchmarks/tunnel/key_numbers.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/tunnel/key_numbers.py"
