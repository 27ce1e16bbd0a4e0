"""Debian's Chromium, headless, driven by Playwright for the report tests.

Playwright launches the system browser (``executable_path``), the ``chromium`` package that
``.ci/run`` installs with apt, not a build downloaded by ``playwright install``: the tests
need nothing beyond the package registry. ``headless_page()`` gives one page of a fresh
browser; the tests then use Playwright's own ``Page`` (``goto``, ``evaluate``,
``wait_for_function``, ``screenshot``, locators).
"""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from contextlib import contextmanager

from playwright.sync_api import Page, sync_playwright


def chromium() -> str | None:
    """Path of the system Chromium.

    Returns
    -------
    str or None
        Debian's ``chromium`` (or ``chromium-browser`` elsewhere) found on ``PATH``, or None
        where neither is installed.
    """
    return shutil.which("chromium") or shutil.which("chromium-browser")


@contextmanager
def headless_page(width_px: int = 1400, height_px: int = 1000, timeout_s: float = 60.0) -> Iterator[Page]:
    """One page of a headless system Chromium, closed with its browser on exit.

    Parameters
    ----------
    width_px, height_px : int
        Size of the viewport, hence of the screenshots, in CSS pixels (device scale 1).
    timeout_s : float
        Default timeout of every navigation, wait and action on the page.

    Yields
    ------
    playwright.sync_api.Page
        A blank page.

    Raises
    ------
    RuntimeError
        If no Chromium is installed.
    """
    exe = chromium()
    if exe is None:
        raise RuntimeError("chromium not found (apt-get install chromium)")
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=exe, headless=True)
        try:
            tab = browser.new_page(viewport={"width": width_px, "height": height_px}, device_scale_factor=1)
            tab.set_default_timeout(timeout_s * 1000)
            yield tab
        finally:
            browser.close()
