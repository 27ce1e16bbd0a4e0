"""Adapter: intermediates -> the six tunnel figures."""

from railradio.io import read_dataset
from railradio.tunnel import figures as f
from railradio.tunnel.study import cable_from_config, tunnel_from_config
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
cfg = smk.params.cfg
cov = cfg["coverage"]
maps = {n: read_dataset(p) for n, p in zip(smk.params.tables, smk.input.maps, strict=True)}
tables = {n: read_dataset(p) for n, p in zip(smk.params.tables, smk.input.tables, strict=True)}
runs = {tuple(k.split("/")): read_dataset(p) for k, p in zip(smk.params.runs, smk.input.runs, strict=True)}
out = dict(zip(smk.params.names, zip(smk.output[0::2], smk.output[1::2], strict=True), strict=True))
f.rssi_map(maps, cov["threshold_dbm"], cov["blind_spot_dbm"], *out["tunnel_rssi_map"])
f.delay_spread(maps, *out["tunnel_delay_spread"])
f.gdop(runs[("hst", "physical_separable")], *out["tunnel_gdop"])
f.position_error_cdf(runs, *out["tunnel_position_error_cdf"], headline=smk.params.cfg["key_measurement"])
f.ray_engines(read_dataset(smk.input.engines), *out["tunnel_ray_engines"])
f.source_vs_physical(
    tables,
    maps,
    tunnel_from_config(cfg, "rect").cross_distance_m,
    cable_from_config(cfg).coupling_loss_db,
    cov["threshold_dbm"],
    *out["tunnel_source_vs_physical"],
)
