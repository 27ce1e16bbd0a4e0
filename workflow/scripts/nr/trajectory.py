"""Adapter: config -> results/nr/trajectory.nc."""

import numpy as np
import xarray as xr

from railradio.io import write_dataset
from railradio.nr.engine.simulate import scenario_from_config
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
setup_script(smk.log[0])
scn = scenario_from_config(dict(smk.params.sim))
t = scn.trajectory.times_s()[: smk.params.n_epochs]
x, v, a = scn.trajectory.state(t)
ds = xr.Dataset(
    {
        "x": (("t",), x, {"units": "m", "long_name": "train position along the track"}),
        "v": (("t",), v, {"units": "m s-1", "long_name": "train speed"}),
        "a": (("t",), a, {"units": "m s-2", "long_name": "train acceleration"}),
        "rrh_x": (("rrh",), scn.deployment.x_m, {"units": "m", "long_name": "RRH position along the track"}),
        "rrh_pci": (("rrh",), scn.deployment.pci(), {"units": "1", "long_name": "RRH physical cell ID"}),
    },
    coords={
        "t": ("t", t, {"units": "s", "long_name": "time"}),
        "rrh": ("rrh", np.arange(scn.deployment.n_rrh), {"units": "1", "long_name": "RRH index"}),
    },
)
write_dataset(ds, smk.output[0], dict(smk.params.sim), None, title="nr trajectory and deployment")
