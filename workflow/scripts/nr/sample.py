"""Adapter: raw IQ and per-block correlations of sample epochs -> results/nr/samples.nc."""
import sys

import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
from common import scenario  # noqa: E402

from railradio.io import write_dataset  # noqa: E402
from railradio.nr.link import ShadowingMap, link_budget  # noqa: E402
from railradio.nr.receiver import Synthesizer  # noqa: E402
from railradio.nr.simulate import KEY_EPOCH, KEY_POOL, KEY_SHADOWING, simulate_epochs  # noqa: E402
from railradio.nr.ssb import qpsk_pool  # noqa: E402
from railradio.rng import make_rng, spawn_key  # noqa: E402
from railradio.workflow import setup_script  # noqa: E402

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
scn = scenario(smk)
dep = scn.deployment
key = spawn_key("nr", 0)  # realization r0: the same draws as its shard
epochs = np.asarray(smk.params.epochs)
ds = simulate_epochs(scn, epochs, smk.params.seed, key, keep_corr_epochs=tuple(int(e) for e in epochs))
# the raw received burst of the first sample epoch, rebuilt from the same keys
e = int(epochs[0])
t = e * scn.trajectory.dt_s
x, v, _ = scn.trajectory.state(np.array([t]))
shadow = ShadowingMap(smk.params.seed, key + (KEY_SHADOWING,), dep, scn.radio)
lb = link_budget(float(x[0]), float(v[0]), dep, scn.radio, scn.rrh_array, scn.train_array, shadow)
syn = Synthesizer(scn.receiver, scn.profile, qpsk_pool(make_rng(smk.params.seed, key + (KEY_POOL,)), scn.pool_size),
                  scn.n_sinusoids, scn.full_channel_range_m, scn.data_beam)
z, s_min = syn(lb.links, make_rng(smk.params.seed, key + (KEY_EPOCH, e)), t0_s=t, d2d_m=lb.link_d2d_m)
fs = scn.receiver.num.sample_rate_hz
start = scn.receiver.num.symbol_start(s_min) / fs
ds["iq"] = (("sample",), z.astype(np.complex64),
            {"units": "W0.5", "long_name": f"received baseband samples of epoch {e} at F_s/{scn.receiver.decimation}"})
ds = ds.assign_coords(sample=("sample", start + np.arange(z.size) / fs,
                              {"units": "s", "long_name": "time from the burst's first subframe start"}))
write_dataset(ds, smk.output[0], dict(smk.params.sim), key, title="nr sample epochs: raw IQ and per-block correlations")
