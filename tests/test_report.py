"""The Snakemake report (``make report``) in a real browser: the CI-scale run's report opened
in headless Chromium (tests/browser.py), its main page, a figure page and the key numbers
beside the source papers' values rendered and photographed; a blank page, a figure missing
from the report or an image that does not load fails.

Chromium is Debian's ``chromium``: the test is skipped where it is missing, unless
``RAILRADIO_REQUIRE_CHROMIUM=1`` (set by ``.ci/run``, which installs it).
"""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from matplotlib.image import imread

from .browser import Browser, chromium
from .conftest import smk

BESIDE = "results/paper/key_numbers_beside_source.html"


@pytest.fixture(scope="module")
def report(ci_run):
    if chromium() is None:
        if os.environ.get("RAILRADIO_REQUIRE_CHROMIUM") == "1":
            pytest.fail("chromium is required here (RAILRADIO_REQUIRE_CHROMIUM=1)")
        pytest.skip("needs chromium (apt-get install chromium)")
    out = ci_run / "results/report.html"
    smk(ci_run, "all", "--report", "results/report.html")
    return out


def _not_blank(png) -> float:
    """Share of the screenshot's pixels that differ from its most common colour."""
    img = imread(png)[:, :, :3]
    flat = (img.reshape(-1, 3) * 255).round().astype(np.int64)
    codes = flat[:, 0] * 65536 + flat[:, 1] * 256 + flat[:, 2]
    _, counts = np.unique(codes, return_counts=True)
    return 1.0 - counts.max() / codes.size


CLICK = (
    "(text => {const el = [...document.querySelectorAll('a, button, li, span, div')]"
    ".filter(e => e.innerText && e.innerText.trim().toLowerCase() === text.toLowerCase()).pop(); "
    "if (!el) return false; el.click(); return true;})"
)
"""Click the innermost element whose text is ``text`` (the report's menu entries; the menu
shows some in capitals)."""
VIEW = (
    "(name => {const row = [...document.querySelectorAll('tr')].find(r => r.innerText.includes(name)); "
    "if (!row) return false; row.querySelector('a[iconname=eye]').click(); return true;})"
)
"""Click the view button (the eye) of the result listed under ``name``."""


def _show(b: Browser, category: str, name: str) -> None:
    """(Results →) category → the result's view button, as a reader clicks them."""
    b.evaluate(CLICK + "('Home')")
    if not b.evaluate(f"document.querySelector('#app').innerText.split('\\n').includes({json.dumps(category)})"):
        b.evaluate(CLICK + "('Results')")
    b.wait_for(f"document.querySelector('#app').innerText.split('\\n').includes({json.dumps(category)})")
    assert b.evaluate(CLICK + f"({json.dumps(category)})"), f"no category {category} in the menu"
    b.wait_for(f"[...document.querySelectorAll('tr')].some(r => r.innerText.includes({json.dumps(name)}))")
    assert b.evaluate(VIEW + f"({json.dumps(name)})"), f"no view button for {name}"


@pytest.mark.slow
def test_the_report_renders_its_figures_and_the_key_numbers_beside_the_sources(report, ci_run, tmp_path):
    figures = sorted(str(p.relative_to(ci_run)) for p in (ci_run / "results/figures").glob("*.png"))
    assert len(figures) > 10
    with Browser() as b:
        b.open(report.as_uri())
        b.wait_for(
            "typeof app !== 'undefined' && document.querySelector('#app').innerText.toLowerCase().includes('results')"
        )
        main = b.screenshot(tmp_path / "main.png")
        assert _not_blank(main) > 0.02, "the main page rendered blank"
        in_report = set(b.evaluate("Object.keys(results)"))
        stems = {r.rsplit(".", 1)[0] for r in in_report}
        missing = [f for f in figures if f.rsplit(".", 1)[0] not in stems]  # each figure as PNG or PDF
        assert not missing, f"figures missing from the report: {missing}"
        assert BESIDE in in_report

        # a figure page, reached through the menu
        target = next(f for f in sorted(in_report) if f.startswith("results/figures/nr_") and f.endswith(".png"))
        _show(b, "nr", target.rsplit("/", 1)[1])
        b.wait_for(
            "[...document.images].some(i => i.src.startsWith('data:image/png') && i.complete && i.naturalWidth > 200)"
        )
        shown = b.evaluate(
            "Math.max(...[...document.images].filter(i => i.src.startsWith('data:image/png'))"
            ".map(i => i.getBoundingClientRect().width))"
        )
        assert shown > 300, f"the figure is shown {shown} px wide"
        page = b.screenshot(tmp_path / "figure.png")
        assert _not_blank(page) > 0.05, "the figure page rendered blank"

        # the key numbers beside the source papers' values
        _show(b, "numbers", BESIDE.rsplit("/", 1)[1])
        b.wait_for("document.querySelector('iframe')")
        table = b.screenshot(tmp_path / "key_numbers.png")
        assert _not_blank(table) > 0.02, "the key-number table rendered blank"
        text = b.evaluate(
            "(u => {const d = u.split(',').slice(1).join(','); "
            "return u.includes(';base64,') ? new TextDecoder().decode("
            "Uint8Array.from(atob(d), c => c.charCodeAt(0))) : decodeURIComponent(d);})"
            "(document.querySelector('iframe').src)"
        )
    numbers = json.loads((ci_run / "results/key_numbers.json").read_text())
    claimed = [k for k, e in numbers.items() if e.get("source_value") is not None]
    assert claimed and all(f"<code>{k}</code>" in text for k in claimed), "a key with a source value is missing"
