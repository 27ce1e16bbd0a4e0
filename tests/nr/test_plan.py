"""The nr plan (railradio.nr.study.plan): read-only, built from a validated config, equal to the
helpers it wraps, and built from the cases and map cells the config check merged and
validated (once per workflow)."""

import dataclasses
import json
import re
import subprocess
import sys
from unittest import mock

import pytest
import yaml

from railradio.codedeps import script_closure
from railradio.config import deep_merge, load_schema, validate_config
from railradio.config_checks import Checked, check_config, main_epochs
from railradio.nr.engine.simulate import scenario_from_config
from railradio.nr.study import cases as nr_cases
from railradio.nr.study import reproduction_map as rm
from railradio.nr.study.plan import CAL_SHARDS, NrPlan, nr_plan, plain
from railradio.nr.study.records import RECORDS
from railradio.nr.study.workflow import receiver_selection, sim_config
from railradio.nr.tracking.measurement import MEASUREMENT_SETS

from ..conftest import COMMAND_TIMEOUT_S, ROOT, copy_workflow, workflow_env
from ..test_codedeps import rule_scripts

SCHEMA = load_schema(ROOT / "workflow/schemas/config.schema.yaml")
NR_SCHEMA = SCHEMA["properties"]["nr"]
RULES = ROOT / "workflow/rules"


def _ci_config():
    paper = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    return validate_config(deep_merge(paper, yaml.safe_load((ROOT / "config/ci.yaml").read_text())), SCHEMA)


@pytest.fixture(scope="module")
def ci():
    """The CI config (validated, every rule checked), the check's result and the plan."""
    cfg = _ci_config()
    checked = check_config(cfg, SCHEMA)
    plan = nr_plan(cfg["nr"], NR_SCHEMA, cases=checked.nr_cases, map_cells=checked.nr_map_cells)
    return cfg, checked, plan


def _same(value, expected):
    """Equal as Snakemake's params hash sees it: the same repr (types, key order, values)."""
    assert repr(value) == repr(expected)


def test_the_plan_is_frozen(ci):
    _, _, plan = ci
    case = next(iter(plan.cases))
    cell = next(iter(plan.map_cells))
    assert plan.cases and plan.map_cells and plan.sweeps
    with pytest.raises(dataclasses.FrozenInstanceError):
        plan.n_epochs = 1
    with pytest.raises(dataclasses.FrozenInstanceError):
        plan.cases = {}
    with pytest.raises(TypeError):
        plan.cases["new_case"] = {}
    with pytest.raises(TypeError):
        del plan.cases[case]
    with pytest.raises(TypeError):
        plan.cases[case]["tracker"] = {}
    with pytest.raises(TypeError):
        plan.cases[case]["tracker"]["gate_prob"] = 0.5
    with pytest.raises(AttributeError):
        plan.cases[case]["tracker"]["q_grid"].append(1.0)
    with pytest.raises(TypeError):
        plan.map_cells[cell]["antenna"]["rrh_elements"] = 1
    with pytest.raises(TypeError):
        plan.sim["radio"]["tx_power_dbm"] = 0.0
    with pytest.raises(TypeError):
        plan.case_n_epochs[case] = 1
    with pytest.raises(AttributeError):
        plan.case_inputs[case]["r0"].append("x.nc")
    with pytest.raises(TypeError):
        plan.sweeps[next(iter(plan.sweeps))]["cases"] = []


def test_the_plan_holds_copies_and_hands_out_plain_copies(ci):
    """Changing what the plan was built from, or what it handed out, changes nothing in it."""
    cfg, _, plan = ci
    checked = check_config(cfg, SCHEMA)
    own = nr_plan(cfg["nr"], NR_SCHEMA, cases=checked.nr_cases, map_cells=checked.nr_map_cells)
    case = next(iter(own.cases))
    checked.nr_cases[case]["tracker"]["gate_prob"] = 0.5
    checked.nr_map_cells.clear()
    handed = plain(own.cases[case])
    handed["tracker"]["q_grid"].append(1e6)
    assert type(handed) is dict and type(handed["tracker"]["q_grid"]) is list
    assert own.cases[case]["tracker"]["gate_prob"] == plan.cases[case]["tracker"]["gate_prob"] != 0.5
    assert own.cases[case]["tracker"]["q_grid"] == plan.cases[case]["tracker"]["q_grid"]
    assert len(own.map_cells) == len(plan.map_cells) > 0


def test_an_unknown_type_is_refused():
    """Freezing refuses what it cannot make read-only (a set could be changed in place)."""
    fields = {f.name: None for f in dataclasses.fields(NrPlan)}
    with pytest.raises(TypeError, match="set"):
        NrPlan(**(fields | {"sweeps": {"s": {"cases": {"a"}}}}))


def test_the_main_run_agrees_with_the_helpers(ci):
    cfg, _, plan = ci
    nr = cfg["nr"]
    assert plan.n_epochs == main_epochs(nr) == 160  # config/ci.yaml: max_epochs
    assert plan.scenario.trajectory.n_epochs == scenario_from_config(nr).trajectory.n_epochs
    assert plan.realizations == tuple(f"r{i}" for i in range(nr["realizations"]))
    assert plan.n_cal_shards == CAL_SHARDS == 2
    _same(plain(plan.sim), sim_config(nr))
    _same(plain(plan.selection), receiver_selection(nr))
    _same(plain(plan.measurement_sets), list(MEASUREMENT_SETS))
    assert plan.fidelity_real == f"r{nr['fidelity']['realization']}"


def test_the_cases_agree_with_the_helpers(ci):
    cfg, _, plan = ci
    nr, sens = cfg["nr"], cfg["nr"]["sensitivity"]
    cases = nr_cases.merged_cases(nr, NR_SCHEMA)
    n_epochs = main_epochs(nr)
    _same(plain(plan.cases), cases)
    assert list(plan.cases) == list(sens["cases"])
    assert plan.sens_base_epochs == min(sens["epochs"], scenario_from_config(nr).trajectory.n_epochs)
    for c, cfg_c in cases.items():
        assert plan.case_n_epochs[c] == nr_cases.case_epochs(cfg_c, sens)
        assert plan.case_n_cal_epochs[c] == nr_cases.case_cal_epochs(cfg_c, nr)
        for run in ("r0", "cal"):
            assert plan.case_n_shards[c][run] == nr_cases.case_n_shards(cfg_c, nr, sens, run, CAL_SHARDS)
            _same(plain(plan.case_inputs[c][run]), nr_cases.case_inputs(c, cases, nr, sens, run, n_epochs, CAL_SHARDS))
        _same(plain(plan.case_sim[c]), sim_config(cfg_c))
        _same(plain(plan.case_selection[c]), receiver_selection(cfg_c))
        assert plan.case_sync_sigma_s[c] == nr_cases.sync_sigma_s(cfg_c)
    _same(plain(plan.sweeps), sens["sweeps"])
    swept = {c for sw in sens["sweeps"].values() for c in sw["cases"]}
    assert plan.unswept_cases == tuple(c for c in cases if c not in swept)
    assert 0 < len(plan.unswept_cases) < len(cases)


def test_the_map_agrees_with_the_helpers(ci):
    cfg, _, plan = ci
    nr = cfg["nr"]
    cells = rm.cells(nr, NR_SCHEMA)
    n_epochs = main_epochs(nr)
    _same(plain(plan.map_cells), cells)
    _same(plain(plan.map_segment), [int(e) for e in nr["map"]["segment"]])
    _same(plain(plan.map_calibration), rm.calibration_section(nr))
    assert plain(plan.map_epochs) == {"r0": list(nr["map"]["segment"]), "cal": [0, nr["map"]["calibration"]["epochs"]]}
    assert dict(plan.map_n_shards) == {"r0": nr["map"]["n_shards"], "cal": 1}
    assert dict(plan.map_rid) == {"r0": 0, "cal": 1001}
    for c, cfg_c in cells.items():
        _same(plain(plan.map_burst_config[c]), rm.burst_config(cfg_c))
        _same(plain(plan.map_selection[c]), receiver_selection(cfg_c))
        expected = {rx: g for rx, g in rm.receivers(nr).items() if rx in rm.cell_receivers(c, nr)}
        _same(plain(plan.map_receivers[c]), expected)
        for run in ("r0", "cal"):
            _same(plain(plan.map_inputs[c][run]), rm.shard_paths(c, run, cells, nr, n_epochs))


def test_the_check_returns_what_it_validated(ci):
    cfg, checked, _ = ci
    assert isinstance(checked, Checked)
    _same(checked.nr_cases, nr_cases.merged_cases(cfg["nr"], NR_SCHEMA))
    _same(checked.nr_map_cells, rm.cells(cfg["nr"], NR_SCHEMA))


def test_the_cases_and_cells_are_merged_and_validated_once():
    """The config check and the plan together merge and validate each case and map cell
    once; a plan given nothing merges and validates them itself (the counters count)."""
    cfg = _ci_config()
    with (
        mock.patch.object(nr_cases, "merged_cases", wraps=nr_cases.merged_cases) as merged,
        mock.patch.object(nr_cases, "validate_config", wraps=validate_config) as case_validations,
        mock.patch.object(rm, "cells", wraps=rm.cells) as cells,
        mock.patch.object(rm, "validate_config", wraps=validate_config) as cell_validations,
    ):
        checked = check_config(cfg, SCHEMA)
        plan = nr_plan(cfg["nr"], NR_SCHEMA, cases=checked.nr_cases, map_cells=checked.nr_map_cells)
        n_cases, n_cells = len(plan.cases), len(plan.map_cells)
        assert n_cases > 0 and n_cells > 0
        assert (merged.call_count, cells.call_count) == (1, 1)
        assert (case_validations.call_count, cell_validations.call_count) == (n_cases, n_cells)
        nr_plan(cfg["nr"], NR_SCHEMA)
        assert (merged.call_count, cells.call_count) == (2, 2)
        assert (case_validations.call_count, cell_validations.call_count) == (2 * n_cases, 2 * n_cells)


def test_the_rule_files_read_the_plan():
    """The workflow plans from the check's result, and the rule files read the plan: no
    other nr global derived from the config, no second merge, no `.get` default."""
    common = (RULES / "common.smk").read_text()
    nr = (RULES / "nr.smk").read_text()
    assert re.search(r"^CONFIG_CHECKED = check_config\(config, CONFIG_SCHEMA\)$", common, re.M)
    assert re.search(r"cases=CONFIG_CHECKED\.nr_cases,\s*map_cells=CONFIG_CHECKED\.nr_map_cells", nr)
    for path in sorted(RULES.glob("*.smk")):
        text = path.read_text()
        assert set(re.findall(r"\bNR_\w+", text)) <= {"NR_PLAN"}, path.name
        assert "merged_cases" not in text and "nr_map.cells" not in text, path.name
        assert not re.search(r"(?<!os\.environ)\.get\(", text), path.name


def test_the_plan_reaches_jobs_through_their_params_only():
    """No job script imports the plan or the config check: a change there re-runs exactly
    the jobs whose params it changes. The published records of the map and the cases, which
    hold no params, record the plan's code beside their rule files."""
    scripts = rule_scripts()
    assert len(scripts) > 40
    for rule, script in scripts.items():
        reached = script_closure(script)
        assert "railradio.nr.study.plan" not in reached and "railradio.config_checks" not in reached, rule
    for name in ("map", "cases"):
        assert "src/railradio/nr/study/plan.py" in RECORDS[name].rule_files


# The workflow itself: a dry run (the Snakefile parsed, the DAG built) with the two
# functions that merge and validate counted.
COUNTED_DRY_RUN = """
import json, sys
from railradio.nr.study import cases, reproduction_map
calls = {"merged_cases": 0, "cells": 0}
for module, name in ((cases, "merged_cases"), (reproduction_map, "cells")):
    def counted(*args, _f=getattr(module, name), _name=name, **kwargs):
        calls[_name] += 1
        return _f(*args, **kwargs)
    setattr(module, name, counted)
from snakemake.cli import main
try:
    main(sys.argv[2:])
finally:
    with open(sys.argv[1], "w") as fh:
        json.dump(calls, fh)
"""


@pytest.mark.slow
def test_a_dry_run_merges_and_validates_the_cases_once(tmp_path):
    wd = copy_workflow(tmp_path)
    script, counts = tmp_path / "counted.py", tmp_path / "counts.json"
    script.write_text(COUNTED_DRY_RUN)
    args = ["-n", "--forceall", "records", "--workflow-profile", "workflow/profiles/default"]
    run = subprocess.run(
        [sys.executable, str(script), str(counts), *args, "--configfile", "config/ci.yaml"],
        cwd=wd,
        env=workflow_env(wd),
        capture_output=True,
        text=True,
        timeout=COMMAND_TIMEOUT_S,
        check=False,
    )
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "nr_case_track" in run.stdout and "nr_map_cell" in run.stdout
    assert json.loads(counts.read_text()) == {"merged_cases": 1, "cells": 1}
