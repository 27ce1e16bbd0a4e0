"""Adapter: one train type, one channel/measurement setup -> results/tunnel/runs/{train}_{setup}.nc."""

from railradio.io import read_dataset, write_dataset
from railradio.rng import spawn_key
from railradio.tunnel.simulate import PROPAGATION_MEASUREMENT_IDS, TRAIN_IDS, run_train
from railradio.tunnel.study import (
    SETUP_DELAY_ERROR,
    SETUPS,
    cable_from_config,
    measurement_from_config,
    run_setup,
    tunnel_from_config,
)
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
log = setup_script(smk.log[0])
cfg = smk.params.cfg
prop, meas = SETUPS[smk.wildcards.setup]
table = read_dataset(smk.input[0])
tunnel = tunnel_from_config(cfg, table.attrs["shape"])
train, cable_error = run_setup(cfg, smk.wildcards.train, smk.wildcards.setup)
over = {"delay_error": SETUP_DELAY_ERROR[smk.wildcards.setup]} if smk.wildcards.setup in SETUP_DELAY_ERROR else {}
ds = run_train(
    table,
    tunnel,
    cable_from_config(cfg),
    train,
    measurement_from_config(cfg, **over),
    prop,
    meas,
    cfg["tracking"],
    smk.params.seed,
    realizations=cfg["realizations"],
    cable_error=cable_error,
)
log.info("%s %s: KF p95 %.3f m", smk.wildcards.train, smk.wildcards.setup, float(ds["kf_err"].quantile(0.95)))
write_dataset(
    ds,
    smk.output[0],
    cfg,
    spawn_key("tunnel", 200, TRAIN_IDS[train.name], PROPAGATION_MEASUREMENT_IDS[(prop, meas)]),
    title=f"tunnel: {train.name} crossing, {prop} channel, {meas} measurements",
)
