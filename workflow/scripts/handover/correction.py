"""Adapter: the joint decision's power correction against the truth -> NetCDF, key numbers, figure."""

from railradio.handover.correction import correction_dataset, correction_key_numbers, plot_correction
from railradio.handover.cost import best_weights
from railradio.handover.params import scenario_from_config
from railradio.io import read_dataset, write_dataset, write_json
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821 - injected by Snakemake
setup_script(smk.log[0])
p = smk.params
scn = scenario_from_config(p.sim)
jt = scn.joint
if jt.m is None or jt.alpha is None:
    m, alpha = best_weights(read_dataset(smk.input.cost), jt.wslr)
    scn = scn.with_weights(m if jt.m is None else jt.m, alpha if jt.alpha is None else jt.alpha)
ds = correction_dataset(scn, list(p.speeds_kmh), p.seed, p.n_blocks, p.runs_per_block)
write_dataset(
    ds,
    smk.output.nc,
    {"sim": scn.to_dict(), "speeds_kmh": list(p.speeds_kmh), "n_blocks": p.n_blocks},
    None,
    title="handover: the joint decision's power correction against the true deviations",
)
write_json(smk.output.json, correction_key_numbers(ds))
plot_correction(ds, smk.output.pdf, smk.output.png)
