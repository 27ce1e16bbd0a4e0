# Study `fusion`: TDOA/AOA fusion with the track constraint (source 002; docs/model/fusion.md).
# Chain: one Monte Carlo job per sweep point -> one dataset per sweep -> figures;
# reference point + sweeps -> key numbers.

FUSION = config["fusion"]
FUSION_SWEEPS = list(FUSION["sweeps"])  # d_m, sigma_tdoa_us, sigma_aoa_rad
FUSION_FIGURE_SWEEP = {
    "distance": "d_m",
    "tdoa_error": "sigma_tdoa_us",
    "aoa_error": "sigma_aoa_rad",
}
from railradio.fusion.montecarlo import sweep_points

# the sensitivity modules are left out: they do not change the main sweeps
FUSION_SENS_MODULES = ("arc.py", "correlated.py", "sensitivity.py", "sensitivity_keys.py", "sensitivity_figures.py")

register_figures("fusion", [f"fusion_rmse_vs_{n}" for n in FUSION_FIGURE_SWEEP] + ["fusion_sensitivity"])
KEY_NUMBER_FRAGMENTS.append("results/fusion/key_numbers.json")
KEY_NUMBER_FRAGMENTS.append("results/sens/fusion/key_numbers.json")


wildcard_constraints:
    sweep="reference|d_m|sigma_tdoa_us|sigma_aoa_rad",
    point=r"\d+",


rule fusion_point:
    """Monte Carlo of one sweep point: per-position error statistics (NetCDF)."""
    output:
        "results/fusion/points/{sweep}/p{point}.nc",
    params:
        point=lambda w: sweep_points(FUSION, w.sweep)[int(w.point)],
        seed=config["seed"],
        chunk_positions=FUSION["chunk_positions"],
    log:
        "results/logs/fusion/point_{sweep}_p{point}.log",
    benchmark:
        "results/benchmarks/fusion/point_{sweep}_p{point}.tsv"
    resources:
        mem_mb=2000,
        runtime=10,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/fusion/point.py"


rule fusion_sweep:
    """Collect the points of one sweep: RMSE, Monte Carlo errors, CRLB (NetCDF)."""
    input:
        lambda w: expand(
            "results/fusion/points/{sweep}/p{point}.nc",
            sweep=w.sweep,
            point=range(len(sweep_points(FUSION, w.sweep))),
        ),
    output:
        "results/fusion/sweep_{sweep}.nc",
    params:
        sweep="{sweep}",
    log:
        "results/logs/fusion/sweep_{sweep}.log",
    benchmark:
        "results/benchmarks/fusion/sweep_{sweep}.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/fusion/sweep.py"


rule fusion_figure:
    """Plot one sweep (source Fig. 3-5) with the CRLB."""
    input:
        lambda w: f"results/fusion/sweep_{FUSION_FIGURE_SWEEP[w.name]}.nc",
    output:
        pdf=report(
            "results/figures/fusion_rmse_vs_{name}.pdf",
            caption="../report/fusion_rmse.rst",
            category="fusion",
        ),
        png="results/figures/fusion_rmse_vs_{name}.png",
    params:
        sweep=lambda w: FUSION_FIGURE_SWEEP[w.name],
    log:
        "results/logs/fusion/figure_{name}.log",
    benchmark:
        "results/benchmarks/fusion/figure_{name}.tsv"
    wildcard_constraints:
        name="distance|tdoa_error|aoa_error",
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/fusion/figure.py"


rule fusion_key_numbers:
    """Key numbers fusion.* from the reference point and the sweeps."""
    input:
        reference="results/fusion/points/reference/p0.nc",
        sweeps=expand("results/fusion/sweep_{sweep}.nc", sweep=FUSION_SWEEPS),
    output:
        "results/fusion/key_numbers.json",
    params:
        sweeps=FUSION_SWEEPS,
    log:
        "results/logs/fusion/key_numbers.log",
    benchmark:
        "results/benchmarks/fusion/key_numbers.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/fusion/key_numbers.py"


# --- Sensitivity beyond the source: curved track, correlated TDOA errors --------
from railradio.fusion.sensitivity import sens_points

FUSION_SENS_POINTS = {kind: sens_points(FUSION, kind) for kind in ("curve", "rho")}  # validates radii


rule fusion_sens_point:
    """Monte Carlo of one sensitivity point (curved track or correlated TDOAs, NetCDF)."""
    output:
        "results/sens/fusion/points/{kind}/p{point}.nc",
    params:
        point=lambda w: FUSION_SENS_POINTS[w.kind][int(w.point)],
        seed=config["seed"],
        chunk_positions=FUSION["chunk_positions"],
    log:
        "results/logs/fusion/sens_point_{kind}_p{point}.log",
    benchmark:
        "results/benchmarks/fusion/sens_point_{kind}_p{point}.tsv"
    wildcard_constraints:
        kind="curve|rho",
        point=r"\d+",
    resources:
        mem_mb=2000,
        runtime=10,
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/fusion/sens_point.py"


rule fusion_sens_sweep:
    """Collect one sensitivity sweep: RMSE per estimator, Monte Carlo errors, CRLB (NetCDF)."""
    input:
        lambda w: expand(
            "results/sens/fusion/points/{kind}/p{point}.nc",
            kind=w.kind,
            point=range(len(FUSION_SENS_POINTS[w.kind])),
        ),
    output:
        "results/sens/fusion/sweep_{kind}.nc",
    params:
        kind="{kind}",
    log:
        "results/logs/fusion/sens_sweep_{kind}.log",
    benchmark:
        "results/benchmarks/fusion/sens_sweep_{kind}.tsv"
    wildcard_constraints:
        kind="curve|rho",
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/fusion/sens_sweep.py"


rule fusion_sens_figure:
    """RMSE against the track curvature and against the TDOA error correlation, with CRLBs."""
    input:
        curve="results/sens/fusion/sweep_curve.nc",
        rho="results/sens/fusion/sweep_rho.nc",
    output:
        pdf=report(
            "results/figures/fusion_sensitivity.pdf",
            caption="../report/fusion_sensitivity.rst",
            category="fusion",
        ),
        png="results/figures/fusion_sensitivity.png",
    log:
        "results/logs/fusion/sens_figure.log",
    benchmark:
        "results/benchmarks/fusion/sens_figure.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/fusion/sens_figure.py"


rule fusion_sens_key_numbers:
    """Key numbers sens.fusion.* from the two sensitivity sweeps."""
    input:
        curve="results/sens/fusion/sweep_curve.nc",
        rho="results/sens/fusion/sweep_rho.nc",
    output:
        "results/sens/fusion/key_numbers.json",
    log:
        "results/logs/fusion/sens_key_numbers.log",
    benchmark:
        "results/benchmarks/fusion/sens_key_numbers.tsv"
    conda:
        "../envs/railradio.yaml"
    script:
        "../scripts/fusion/sens_key_numbers.py"
