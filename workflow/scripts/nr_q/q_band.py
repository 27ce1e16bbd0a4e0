"""Adapter: calibration and evaluation shards + calibration -> results/nr/q_band/{q_band.nc,key_numbers.json}."""

import json

from railradio.io import write_dataset, write_json
from railradio.nr.engine.simulate import scenario_from_config
from railradio.nr.study.q_band import Q_BAND_ID, key_numbers, q_band
from railradio.nr.study.runs import point_model, read_shards
from railradio.rng import make_rng, spawn_key
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
p = smk.params
cal = json.loads(open(smk.input.calibration, encoding="utf-8").read())
n = int(p.n_shards)
runs = [point_model(read_shards(smk.input.runs[i : i + n]), p.tracker) for i in range(0, len(smk.input.runs), n)]
qb = q_band(
    point_model(read_shards(smk.input.cal), p.tracker),
    runs,
    scenario_from_config(dict(p.sim)),
    cal,
    p.tracker,
    p.selection,
    make_rng(int(p.seed), spawn_key("nr", Q_BAND_ID)),
    float(p.sim["deployment"]["spacing_m"]),
)
log.info("q band: %s", qb.to_dataframe().to_string())
cfg = {"sim": dict(p.sim), "tracker": dict(p.tracker)}
write_dataset(qb, smk.output.nc, cfg, spawn_key("nr", Q_BAND_ID), "nr: q as a band")
write_json(smk.output.numbers, key_numbers(qb))
