"""Adapter: maps, tables, engines, runs -> results/tunnel/key_numbers.json."""

from railradio.io import read_dataset, write_json
from railradio.tunnel.keys import key_numbers
from railradio.tunnel.study import cable_from_config, eps_from_config, tunnel_from_config
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
cov = smk.params.cfg["coverage"]
maps = {n: read_dataset(p) for n, p in zip(smk.params.tables, smk.input.maps, strict=True)}
tables = {n: read_dataset(p) for n, p in zip(smk.params.tables, smk.input.tables, strict=True)}
runs = {tuple(k.split("/")): read_dataset(p) for k, p in zip(smk.params.runs, smk.input.runs, strict=True)}
sens = {n: read_dataset(p) for n, p in zip(smk.params.trains, smk.input.sens, strict=True)}
write_json(
    smk.output[0],
    key_numbers(
        runs,
        maps,
        tables,
        read_dataset(smk.input.engines),
        cov["threshold_dbm"],
        cov["blind_spot_dbm"],
        cov["min_rays"],
        cable_from_config(smk.params.cfg).wavelength_m,
        tunnel_from_config(smk.params.cfg, "rect").width_m,
        eps_from_config(smk.params.cfg),
        sens=sens,
        peak_bias=read_dataset(smk.input.peak_bias),
        side_wall_map=read_dataset(smk.input.side_wall_map),
        headline=smk.params.cfg["key_measurement"],
        slot_spacing_m=smk.params.cfg["geometry"]["slot_spacing_m"],
    ),
)
