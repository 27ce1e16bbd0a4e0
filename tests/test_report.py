"""The Snakemake report (``make report``) in a real browser: the CI-scale run's report opened
in headless Chromium (Debian's ``chromium`` driven by Playwright, tests/browser.py), its main
page, a figure page and the key numbers beside the source papers' values rendered and
photographed; a blank page, a figure missing from the report or an image that does not load
fails.

Chromium is Debian's ``chromium``: the test is skipped where it is missing, unless
``RAILRADIO_REQUIRE_CHROMIUM=1`` (set by ``.ci/run``, which installs it).
"""

from __future__ import annotations

import io
import json
import os

import numpy as np
import pytest
from matplotlib.image import imread
from playwright.sync_api import Page

from .browser import chromium, headless_page
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


def _not_blank(png: bytes) -> float:
    """Share of the screenshot's pixels that differ from its most common colour."""
    img = imread(io.BytesIO(png))[:, :, :3]
    flat = (img.reshape(-1, 3) * 255).round().astype(np.int64)
    codes = flat[:, 0] * 65536 + flat[:, 1] * 256 + flat[:, 2]
    _, counts = np.unique(codes, return_counts=True)
    return 1.0 - counts.max() / codes.size


def _show(tab: Page, category: str, name: str) -> None:
    """(Results →) category → the result's view button, clicked as a reader clicks them.

    Parameters
    ----------
    tab : playwright.sync_api.Page
        The report, open on any of its pages.
    category : str
        The menu entry the result is listed under.
    name : str
        The result's file name (its row in the category's table).
    """
    entry = tab.get_by_text(category, exact=True)
    if not entry.is_visible():  # on a result's page the menu lists its category's results
        tab.get_by_text("Results", exact=True).click()
    entry.click()
    tab.locator("tr", has_text=name).first.locator("a[iconname=eye]").click()


@pytest.mark.slow
def test_the_report_renders_its_figures_and_the_key_numbers_beside_the_sources(report, ci_run, tmp_path):
    figures = sorted(str(p.relative_to(ci_run)) for p in (ci_run / "results/figures").glob("*.png"))
    assert len(figures) > 10
    with headless_page() as tab:
        tab.goto(report.as_uri())
        tab.wait_for_function(
            "typeof app !== 'undefined' && document.querySelector('#app').innerText.toLowerCase().includes('results')"
        )
        main = tab.screenshot(path=tmp_path / "main.png")
        assert _not_blank(main) > 0.02, "the main page rendered blank"
        in_report = set(tab.evaluate("Object.keys(results)"))
        stems = {r.rsplit(".", 1)[0] for r in in_report}
        missing = [f for f in figures if f.rsplit(".", 1)[0] not in stems]  # each figure as PNG or PDF
        assert not missing, f"figures missing from the report: {missing}"
        assert BESIDE in in_report

        # a figure page, reached through the menu
        target = next(f for f in sorted(in_report) if f.startswith("results/figures/nr_") and f.endswith(".png"))
        _show(tab, "nr", target.rsplit("/", 1)[1])
        tab.wait_for_function(
            "[...document.images].some(i => i.src.startsWith('data:image/png') && i.complete && i.naturalWidth > 200)"
        )
        shown = tab.evaluate(
            "Math.max(...[...document.images].filter(i => i.src.startsWith('data:image/png'))"
            ".map(i => i.getBoundingClientRect().width))"
        )
        assert shown > 300, f"the figure is shown {shown} px wide"
        figure = tab.screenshot(path=tmp_path / "figure.png")
        assert _not_blank(figure) > 0.05, "the figure page rendered blank"

        # the key numbers beside the source papers' values, as the report's frame renders them
        _show(tab, "numbers", BESIDE.rsplit("/", 1)[1])
        table = tab.frame_locator("iframe").locator("body")
        table.locator("code").first.wait_for()
        shot = tab.screenshot(path=tmp_path / "key_numbers.png")
        assert _not_blank(shot) > 0.02, "the key-number table rendered blank"
        text = table.inner_html()
    numbers = json.loads((ci_run / "results/key_numbers.json").read_text())
    claimed = [k for k, e in numbers.items() if e.get("source_value") is not None]
    assert claimed and all(f"<code>{k}</code>" in text for k in claimed), "a key with a source value is missing"


TABLE = "results/paper/key_numbers_table.html"


@pytest.mark.slow
def test_the_report_filters_and_sorts_every_key_number(report, ci_run, tmp_path):
    """The filterable table, opened in the report as a reader opens it: all keys listed, a
    column filter (study, verdict) keeps exactly the matching rows, a header click sorts."""
    from railradio.keytable import COLUMNS, rows

    table = rows(json.loads((ci_run / "results/key_numbers.json").read_text()))
    with headless_page() as tab:
        tab.goto(report.as_uri())
        tab.wait_for_function("typeof app !== 'undefined'")
        _show(tab, "numbers", TABLE.rsplit("/", 1)[1])
        frame = tab.frame_locator("iframe")
        frame.locator("body[data-ready=true]").wait_for()
        info = frame.locator(".dt-info").first
        assert f"of {len(table):,} entries" in info.inner_text()
        study = next(r["study"] for r in table if r["study"] == "fusion")
        frame.locator("tfoot input").nth(COLUMNS.index("study")).fill(study)
        want = [r for r in table if study in r["study"]]
        tab.wait_for_timeout(300)
        assert f"of {len(want):,} entries (filtered from {len(table):,}" in info.inner_text()
        frame.locator("thead th").nth(COLUMNS.index("key")).click()  # sort by key, descending after ascending
        frame.locator("thead th").nth(COLUMNS.index("key")).click()
        tab.wait_for_timeout(300)
        first = frame.locator("tbody tr").first.locator("td").first.inner_text()
        assert first == max(r["key"] for r in want)
        shot = tab.screenshot(path=tmp_path / "table.png")
        assert _not_blank(shot) > 0.02, "the filterable table rendered blank"
