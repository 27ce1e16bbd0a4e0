"""Adapter: shards -> rates and means per policy and speed (or per sensitivity case)."""

import numpy as np
import xarray as xr

from railradio.handover.summary import metrics_dataset, policy_metrics
from railradio.io import read_dataset, write_dataset
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
log = setup_script(smk.log[0])
p = smk.params
groups = {}  # coordinate value -> list of shard datasets
for path, key in zip(smk.input, p.groups, strict=True):
    groups.setdefault(key, []).append(read_dataset(path))
metrics = {}
for key, parts in groups.items():
    ds = xr.concat(parts, dim="run", data_vars="minimal") if len(parts) > 1 else parts[0]
    pols = ds.attrs["policies"].split(",")
    metrics[key] = {pol: policy_metrics(ds, pol) for pol in pols}
coords = list(groups)
if p.dim == "speed_kmh":
    out = metrics_dataset(
        metrics, "speed_kmh", {"units": "km/h", "long_name": "train speed"}, [float(c) for c in coords]
    )
else:  # sensitivity: policies not affected by a case are NaN there
    allp = list(p.policies)
    for key in coords:
        for pol in allp:
            if pol not in metrics[key]:
                metrics[key][pol] = {n: np.nan for n in next(iter(metrics[key].values()))}
        metrics[key] = {pol: metrics[key][pol] for pol in allp}
    out = metrics_dataset(metrics, "case", {"units": "1", "long_name": "sensitivity case"}, coords)
    info = dict(p.cases)
    out["switch"] = (
        "case",
        [info[c].get("switch", "none") for c in coords],
        {"units": "1", "long_name": "config switch changed"},
    )
    out["value"] = (
        "case",
        [str(info[c].get("value", "reference")) for c in coords],
        {"units": "1", "long_name": "its value"},
    )
    out["affected"] = (
        ("case", "policy"),
        np.array([[np.isfinite(metrics[c][pol]["success"]) for pol in allp] for c in coords]),
        {"units": "1", "long_name": "the switch can change this policy"},
    )
    out["speed_kmh"] = ((), float(p.speed_kmh), {"units": "km/h", "long_name": "train speed"})
write_dataset(
    out,
    smk.output[0],
    {"dim": p.dim, "keys": list(p.groups)},
    None,
    title=f"handover: rates and means per policy and {p.dim}",
)
log.info("wrote %s", smk.output[0])
