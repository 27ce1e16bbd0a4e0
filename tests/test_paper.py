"""The manuscript's macros without LaTeX: every ``\\kn``, ``\\knm``, ``\\knsrc``, ``\\cfg`` and
``\\cfgn`` key in ``paper/main.tex`` exists (the PDF build itself is tests/test_workflow.py's);
no published tracker accuracy exceeds 10 km."""

from __future__ import annotations

import json
import re

import yaml

from railradio.keynumbers import _flatten, config_to_latex

from .conftest import ROOT

TEX = re.sub(r"(?<!\\)%.*", "", (ROOT / "paper/main.tex").read_text(encoding="utf-8"))  # comments out


def _keys(macro: str) -> set[str]:
    return set(re.findall(r"\\" + macro + r"\{([^}]*)\}", TEX))


def test_every_key_number_the_paper_cites_is_published():
    """In the published paper-scale numbers and in the CI scale's expected ones (which the
    CI run must reproduce, so the code still makes every cited key)."""
    published = json.loads((ROOT / "paper/numbers.json").read_text())
    ci = json.loads((ROOT / "tests/expected/key_numbers_ci.json").read_text())
    cited = _keys("kn") | _keys("knsrc") | _keys("knm")
    assert len(cited) > 100
    assert not cited - set(published), sorted(cited - set(published))
    assert not cited - set(ci), sorted(cited - set(ci))
    for name in _keys("knsrc"):  # a source claim cited must exist
        assert published[name]["source_value"] is not None, name


def test_every_config_value_the_paper_cites_exists():
    with open(ROOT / "config/config.yaml") as fh:
        cfg = yaml.safe_load(fh)
    defined = set(re.findall(r"\\@namedef\{cfg@([^}]*)\}", config_to_latex(cfg)))
    lists = set(re.findall(r"\\@namedef\{cfgn@([^}]*)\}", config_to_latex(cfg)))
    assert _keys("cfg") and not _keys("cfg") - defined, sorted(_keys("cfg") - defined)
    assert not _keys("cfgn") - lists, sorted(_keys("cfgn") - lists)
    assert set(_flatten(cfg)) <= defined


def test_no_macro_key_is_built_from_parts():
    """Keys are literal (a key assembled with \\csname or #1 would escape the checks above)."""
    for macro in ("kn", "knsrc", "knm", "cfg", "cfgn"):
        assert not any(re.search(r"[\\#]", k) for k in _keys(macro)), macro


def test_no_published_nr_accuracy_exceeds_10_km():
    """A lost track is a lost share, never a mean error of 10^19 m."""
    from railradio.nr.tracking.loss import ACCURACY_CAP_M

    published = json.loads((ROOT / "paper/numbers.json").read_text())
    bad = {
        k: e["value"]
        for k, e in published.items()
        if k.startswith(("nr.", "sens.nr."))
        and ".err_m." in k
        and e["value"] is not None
        and e["value"] > ACCURACY_CAP_M
    }
    assert not bad, bad
