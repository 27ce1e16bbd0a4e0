"""Adapter: raw IQ and per-block correlations of sample epochs -> results/nr/samples.nc."""
import sys

import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
from common import scenario  # noqa: E402

from railradio.io import write_dataset  # noqa: E402
from railradio.nr.simulate import simulate_epochs  # noqa: E402
from railradio.rng import spawn_key  # noqa: E402
from railradio.workflow import setup_script  # noqa: E402

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
scn = scenario(smk)
key = spawn_key("nr", 0)  # realization r0: the same draws as its shard
epochs = np.asarray(smk.params.epochs)
ds = simulate_epochs(scn, epochs, smk.params.seed, key, keep_corr_epochs=tuple(int(e) for e in epochs))
write_dataset(ds, smk.output[0], dict(smk.params.sim), key, title="nr sample epochs with per-block correlations")
