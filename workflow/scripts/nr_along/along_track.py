"""Adapter: evaluation shards + calibration + IMM runs -> results/nr/along/{along_track.nc,key_numbers.json}."""

import json

from railradio.io import read_dataset, write_dataset, write_json
from railradio.nr.engine.simulate import scenario_from_config
from railradio.nr.study.along_track import along_track, key_numbers
from railradio.nr.study.runs import point_model, read_shards
from railradio.workflow import setup_script

smk = snakemake  # noqa: F821
log = setup_script(smk.log[0])
p = smk.params
cal = json.loads(open(smk.input.calibration, encoding="utf-8").read())
n = int(p.n_shards)
runs = [point_model(read_shards(smk.input.runs[i : i + n]), p.tracker) for i in range(0, len(smk.input.runs), n)]
scn = scenario_from_config(dict(p.sim))
imm = [read_dataset(f) for f in smk.input.imm]
at = along_track(runs, scn, cal, p.tracker, p.selection, float(p.sim["deployment"]["spacing_m"]), imm)
log.info("along/cross-track: %s", at.drop_dims(["risk", "filter"]).to_dataframe().to_string())
log.info("IMM runs: %s", at.drop_dims(["receiver", "measurements", "gate", "model", "risk"]).to_dataframe().to_string())
cfg = {"sim": dict(p.sim), "tracker": dict(p.tracker), "calibration": cal}
write_dataset(at, smk.output.nc, cfg, None, "nr: along-track and cross-track errors, protection level")
write_json(smk.output.numbers, key_numbers(at))
