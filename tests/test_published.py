"""Published records (railradio.published): CI reads them instead of re-running their
targets, so a stale record must fail here, and the merge must read only a current one."""

import json
import subprocess
from pathlib import Path

import pytest
import yaml

from railradio.config import load_schema, validate_config
from railradio.nr.study.records import RECORDS
from railradio.published import Record

from .conftest import ROOT


def _config() -> dict:
    config = yaml.safe_load((ROOT / "config/config.yaml").read_text(encoding="utf-8"))
    return validate_config(config, load_schema(ROOT / "workflow/schemas/config.schema.yaml"))


@pytest.mark.parametrize("name", sorted(RECORDS))
def test_published_records_are_from_this_code_and_config(name):
    """paper/<name>_numbers.json comes from `make <name>`: its provenance must name the code
    and config that are here, or its numbers are stale (re-run `make republish`)."""
    assert RECORDS[name].stale(ROOT, _config()) == [], (
        f"paper/{name}_numbers.json is stale: re-run `make republish` "
        "(the three records, then the paper-scale merge and the CI expectation)"
    )


def test_republish_publishes_every_record_before_the_merge_that_reads_them():
    """`make republish` (dry run): the three records are published before the paper-scale merge
    copied to paper/numbers.json, and the CI expectation is made last (its merge reads the
    fidelity record). A merge that ran before a record's publication carried the old record into
    paper/numbers.json, which CI's reproduction then found beyond tolerance."""
    lines = subprocess.run(
        ["make", "-n", "--no-print-directory", "republish"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.splitlines()

    def at(pattern: str, but: str = "\0") -> int:
        hits = [i for i, line in enumerate(lines) if pattern in line and but not in line]
        assert len(hits) == 1, (pattern, lines)
        return hits[0]

    published = [at(f"railradio.nr.study.records publish {name} ") for name in sorted(RECORDS)]
    merge = at("snakemake numbers -j", but="(cd ")  # the paper-scale merge, not the CI-scale one
    copy = at("cp results/key_numbers.json paper/numbers.json")
    expected = at("--configfile config/ci.yaml")
    assert at("snakemake records fidelity") < min(published)
    assert max(published) < merge < copy < expected


def test_a_record_goes_stale_with_its_code_its_rule_file_or_its_config(tmp_path):
    root = tmp_path
    (root / "paper").mkdir()
    (root / "workflow/scripts").mkdir(parents=True)
    (root / "workflow/rules").mkdir(parents=True)
    script, rules = root / "workflow/scripts/t.py", root / "workflow/rules/t.smk"
    script.write_text("import json\n", encoding="utf-8")
    rules.write_text("rule t:\n    output: 'x'\n", encoding="utf-8")
    rec = Record("t", ("workflow/scripts/t.py",), lambda c: {"a": c["a"]}, rule_files=("workflow/rules/t.smk",))
    assert rec.stale(root, {"a": 1}) == ["not published"]
    numbers = tmp_path / "k.json"
    numbers.write_text(json.dumps({"t.x": {"value": 1.0}}), encoding="utf-8")
    rec.publish(numbers, root, {"a": (1, 2)})
    assert json.loads((root / rec.numbers_file).read_text()) == {"t.x": {"value": 1.0}}
    assert rec.stale(root, {"a": [1, 2]}) == []  # as JSON reads it back
    assert rec.fragment(root, {"a": [1, 2]}, "results/t.json") == rec.numbers_file  # the merge reads the record
    assert rec.stale(root, {"a": [1, 3]}) == ["config"]
    assert rec.fragment(root, {"a": [1, 3]}, "results/t.json") == "results/t.json"  # else the run's own
    script.write_text("import json  # a comment is not code\n", encoding="utf-8")
    assert rec.stale(root, {"a": [1, 2]}) == []
    script.write_text("import json\nimport os\n", encoding="utf-8")
    assert rec.stale(root, {"a": [1, 2]}) == ["code"]
    script.write_text("import json\n", encoding="utf-8")
    rules.write_text("rule t:\n    output: 'y'\n", encoding="utf-8")
    assert rec.stale(root, {"a": [1, 3]}) == ["code", "config"]


@pytest.mark.parametrize(
    ("name", "prefixes", "ci_reads_record"),
    [
        ("map", ("nr.map.",), False),  # CI runs the map and the cases at its own scale
        ("cases", ("sens.nr.",), False),
        ("fidelity", ("nr.fidelity.", "nr.detector."), True),  # every merge reads the record
    ],
)
def test_nr_records_hold_their_targets_keys_and_nothing_else(name, prefixes, ci_reads_record):
    """A record replaces its target's fragment: the same keys as that fragment at CI scale
    (all under its prefixes), and the published paper numbers carry them unchanged, since
    `make reproduce` merges the record and compares with paper/numbers.json; so does the CI
    expectation where the CI-scale merge reads the record too."""
    published = json.loads((ROOT / RECORDS[name].numbers_file).read_text(encoding="utf-8"))
    ci = json.loads((ROOT / "tests/expected/key_numbers_ci.json").read_text(encoding="utf-8"))
    assert set(published) == {k for k in ci if k.startswith(prefixes)}
    if ci_reads_record:
        assert {k: ci[k] for k in published} == published
    paper = json.loads((ROOT / "paper/numbers.json").read_text(encoding="utf-8"))
    changed = sorted(k for k in published if paper.get(k) != published[k])
    assert changed == [], f"paper/numbers.json holds another {name} record than its own: {changed[:5]}"


def test_records_name_existing_files():
    for rec in RECORDS.values():
        for f in (*rec.scripts, *rec.rule_files):
            assert Path(ROOT / f).is_file(), f
