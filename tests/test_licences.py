"""The project is MIT: no dependency, direct or transitive, may be licensed under the GPL
only (a GPL-only library would make the whole program GPL)."""

from __future__ import annotations

import re
from importlib.metadata import PackageNotFoundError, distribution

from packaging.requirements import Requirement

NO_METADATA = {  # distributions that declare no licence in their metadata: checked by hand
    "conda-inject": "MIT",
    "snakemake-interface-common": "MIT",
    "snakemake-interface-logger-plugins": "MIT",
    "snakemake-interface-report-plugins": "MIT",
    "snakemake-interface-scheduler-plugins": "MIT",
    "snakemake-interface-storage-plugins": "MIT",
}
_GPL = re.compile(r"\b(A?GPL|General Public License)", re.I)
_LGPL = re.compile(r"\b(LGPL|Lesser General Public)", re.I)


def _closure(root: str = "railradio") -> dict[str, list[str]]:
    """distribution -> its declared licences (expression, field, classifiers), over the
    install requirements of ``root`` and its test extra, transitively."""
    seen: dict[str, list[str]] = {}
    todo = [root]
    while todo:
        name = todo.pop()
        key = name.lower().replace("_", "-")
        if key in seen:
            continue
        try:
            dist = distribution(name)
        except PackageNotFoundError:  # an optional or platform-specific requirement
            continue
        md = dist.metadata
        seen[key] = [x for x in (md.get("License-Expression"), md.get("License")) if x] + [
            c for c in (md.get_all("Classifier") or []) if c.startswith("License ::")
        ]
        for r in dist.requires or []:
            req = Requirement(r)
            if req.marker is None or any(req.marker.evaluate({"extra": e}) for e in ("", "test")):
                todo.append(req.name)
    return seen


def _gpl_only(licences: list[str]) -> bool:
    strong = [x for x in licences if _GPL.search(x) and not _LGPL.search(x)]
    return bool(strong) and len(strong) == len(licences)


def test_no_dependency_is_gpl_only():
    closure = _closure()
    assert len(closure) > 40 and "numpy" in closure and "pytest-timeout" in closure
    unknown = sorted(k for k, v in closure.items() if not v and k not in NO_METADATA and k != "railradio")
    assert not unknown, f"licence unknown, check and add to NO_METADATA: {unknown}"
    gpl = sorted(k for k, v in closure.items() if _gpl_only(v))
    assert not gpl, gpl


def test_the_rule_catches_a_gpl_only_licence():
    assert _gpl_only(
        [
            "GPL-2.0-or-later",  # ducc0's
            "License :: OSI Approved :: GNU General Public License v2 or later (GPLv2+)",
        ]
    )
    assert not _gpl_only(
        [
            "License :: Public Domain",
            "License :: OSI Approved :: BSD License",
            "License :: OSI Approved :: GNU General Public License (GPL)",
        ]
    )  # docutils: a choice
    assert not _gpl_only(["LGPL-3.0-or-later"]) and not _gpl_only(["MIT"])
