"""Adapter: one train type through the sensitivity cases -> results/tunnel/sens/{train}.nc."""

from railradio.io import read_dataset, write_dataset
from railradio.rng import spawn_key
from railradio.tunnel.sensitivity import make_sensitivity
from railradio.tunnel.simulate import TRAIN_IDS
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
log = setup_script(smk.log[0])
cfg = smk.params.cfg
train = smk.wildcards.train
ds = make_sensitivity(
    cfg, read_dataset(smk.input.table), train, smk.params.seed, side_wall_table=read_dataset(smk.input.side_wall)
)
for case, v in zip(ds["case"].values, ds["err_p95_m"].values, strict=True):
    log.info("%s %s: KF p95 %.3f m", train, case, v)
write_dataset(
    ds, smk.output[0], cfg, spawn_key("tunnel", 500, TRAIN_IDS[train]), title=f"tunnel: sensitivity cases, {train}"
)
