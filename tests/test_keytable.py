"""The key numbers as data (railradio.keytable): the verdict rule on each relation, the tidy
CSV, and docs/keys.md current with paper/numbers.json."""

from __future__ import annotations

import csv
import io
import json
import re

import pytest

from railradio.keytable import COLUMNS, half_unit, markdown, rows, study_of, to_csv, verdict

from .conftest import ROOT


def _e(value, rel, src, se=None):
    return {"value": value, "source_relation": rel, "source_value": src, "mc_stderr": se}


@pytest.mark.parametrize(
    ("entry", "want"),
    [
        (_e(1.0, "<", 1.7, 0.1), "holds"),  # 0.7 below, beyond 2 SE
        (_e(1.6, "<", 1.7, 0.1), "undecided"),  # within 2 SE
        (_e(2.0, "<", 1.7, 0.1), "fails"),
        (_e(1.7, "≤", 1.7, None), "holds"),  # no MC error: the bound itself meets ≤
        (_e(1.7, "<", 1.7, None), "fails"),  # ... but not <
        (_e(0.999, "≥", 0.9975, 0.0), "holds"),
        (_e(0.97, "≥", 0.9975, 0.001), "fails"),
        (_e(50.0, ">", 45.0, 1.0), "holds"),
        (_e(0.664, "=", 0.66, None), "agrees"),  # within half a unit of the printed 0.66
        (_e(0.67, "=", 0.66, None), "ours higher"),
        (_e(0.67, "=", 0.66, 0.01), "agrees"),  # within 2 SE
        (_e(0.5, "≈", 0.75, 0.0), "ours lower"),
        (_e(None, "=", 0.66), "no value"),
        (_e(1.0, None, None), ""),
    ],
)
def test_verdict_rule(entry, want):
    assert verdict(entry) == want


def test_verdict_rejects_an_unknown_relation_and_reads_printed_digits():
    with pytest.raises(ValueError, match="source_relation"):
        verdict(_e(1.0, "!=", 2.0))
    assert (half_unit(0.66), half_unit(3.5), half_unit(3), half_unit(0.9975)) == pytest.approx(
        (0.005, 0.05, 0.5, 0.00005)
    )
    assert study_of("sens.nr.tdl_a.x") == "nr" and study_of("tunnel.hst.err_m.p95") == "tunnel"


def test_csv_holds_every_key_once_with_its_columns():
    numbers = json.loads((ROOT / "paper/numbers.json").read_text(encoding="utf-8"))
    table = list(csv.DictReader(io.StringIO(to_csv(numbers))))
    assert tuple(table[0]) == COLUMNS
    assert [r["key"] for r in table] == sorted(numbers)
    claims = [r for r in rows(numbers) if r["source_value"] is not None]
    assert claims and all(r["verdict"] for r in claims)


def test_docs_keys_md_is_current():
    numbers = json.loads((ROOT / "paper/numbers.json").read_text(encoding="utf-8"))
    current = (ROOT / "docs/keys.md").read_text(encoding="utf-8")
    assert current == markdown(numbers), (
        "docs/keys.md is stale: python -m railradio.keytable docs paper/numbers.json docs/keys.md"
    )


@pytest.mark.slow
def test_the_ci_run_writes_the_csv_beside_the_json(ci_run):
    numbers = json.loads((ci_run / "results/key_numbers.json").read_text(encoding="utf-8"))
    text = (ci_run / "results/key_numbers.csv").read_text(encoding="utf-8")
    assert text == to_csv(numbers)


def test_study_summary_counts_keys_and_claims_per_study():
    from railradio.keytable import study_summary, study_summary_latex

    numbers = {
        "fusion.a": {"value": 1.0, "mc_stderr": 0.0, "source_value": 2.0, "source_relation": "<"},
        "fusion.b": {"value": 3.0, "mc_stderr": 0.0},
        "handover.c": {"value": 3.0, "mc_stderr": 0.0, "source_value": 2.0, "source_relation": "<"},
        "handover.d": {"value": 2.0, "mc_stderr": 1.0, "source_value": 2.5, "source_relation": ">"},
    }
    rows = {r["study"]: r for r in study_summary(numbers)}
    assert rows["fusion"] == {"study": "fusion", "keys": 2, "claims": 1, "met": 1, "not met": 0, "undecided": 0}
    assert rows["handover"] == {"study": "handover", "keys": 2, "claims": 2, "met": 0, "not met": 1, "undecided": 1}
    tex = study_summary_latex(numbers)
    assert tex.startswith("\\begin{tabular}") and "handover & 2 & 2 & 0 & 1 & 1" in tex


def test_the_filterable_table_holds_every_key_and_loads_nothing():
    from railradio.keyhtml import filterable_table, unpack_rows

    numbers = {
        "fusion.a": {"value": 1.23456, "unit": "m", "mc_stderr": 0.01, "source_value": 2.0, "source_relation": "<"},
        "nr.b_<i>": {"value": None, "unit": "1", "description": "lost & found"},
    }
    page = filterable_table(numbers)
    assert page.startswith("<!DOCTYPE html>") and "2 keys" in page
    got = {r[0]: dict(zip(COLUMNS, r, strict=True)) for r in unpack_rows(page)}
    assert set(got) == set(numbers)
    assert got["fusion.a"]["value"] == "1.235" and got["fusion.a"]["verdict"] == "holds"
    assert got["fusion.a"]["source_value"] == "2" and got["fusion.a"]["mc_stderr"] == "0.01000"
    assert got["nr.b_<i>"]["value"] == "" and got["nr.b_<i>"]["description"] == "lost & found"
    assert "nr.b_<i>" not in page  # packed, and shown as text (DataTable.render.text)
    assert len(page) < 1_000_000  # the report embeds it as a data: URL, which Chromium caps at 2 MB
    assert not re.search(r"<(?:script|link)[^>]+(?:src|href)=[\"']?https?:", page)  # offline: nothing fetched
    with pytest.raises(ValueError, match="numbers"):
        filterable_table({})


@pytest.mark.slow
def test_the_ci_run_writes_the_filterable_table(ci_run):
    numbers = json.loads((ci_run / "results/key_numbers.json").read_text(encoding="utf-8"))
    from railradio.keyhtml import unpack_rows

    page = (ci_run / "results/paper/key_numbers_table.html").read_text(encoding="utf-8")
    assert f"{len(numbers)} keys" in page
    assert [r[0] for r in unpack_rows(page)] == sorted(numbers)
