"""Adapter: raw IQ and per-block correlations of sample epochs -> results/nr/samples.nc."""

import numpy as np

from railradio.io import write_dataset
from railradio.nr.engine.epochs import simulate_epochs
from railradio.nr.engine.simulate import Synthesis, scenario_from_config
from railradio.nr.receiver.cellsearch import warmup_start
from railradio.rng import spawn_key
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
scn = scenario_from_config(dict(smk.params.sim))
key = spawn_key("nr", 0)  # realization r0: the same draws as its shard
epochs = np.asarray(smk.params.epochs)
ds = simulate_epochs(scn, epochs, smk.params.seed, key, keep_corr_epochs=tuple(int(e) for e in epochs))
# the raw received burst of the first sample epoch, rebuilt from the same keys (the
# network's serving-cell state replayed from its last restart, as in the shard)
e = int(epochs[0])
synth = Synthesis(scn, smk.params.seed, key)
for w in range(warmup_start(e, scn.serving.reset_every), e):
    synth.advance(w)
burst = synth(e)
z, s_min = burst.z, burst.s_min
fs = scn.receiver.num.sample_rate_hz
start = scn.receiver.num.symbol_start(s_min) / fs
ds["iq"] = (
    ("sample",),
    z.astype(np.complex64),
    {
        "units": "W0.5",
        "long_name": f"received baseband samples of epoch {e}: the front end's, at F_s/{scn.receiver.decimation}",
    },
)
ds = ds.assign_coords(
    sample=(
        "sample",
        start + np.arange(z.size) / fs,
        {"units": "s", "long_name": "time from the burst's first subframe start"},
    )
)
write_dataset(ds, smk.output[0], dict(smk.params.sim), key, title="nr sample epochs: raw IQ and per-block correlations")
