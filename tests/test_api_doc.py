"""docs/api.md names only what exists: every dotted ``railradio.…`` name in it resolves to a
module or an attribute of one (the page is a reference, and a renamed function must not
leave it behind)."""

from __future__ import annotations

import importlib
import re

from .conftest import ROOT


def _resolves(name: str) -> bool:
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for attr in parts[i:]:
            if not hasattr(obj, attr):
                return False
            obj = getattr(obj, attr)
        return True
    return False


def test_every_api_name_exists():
    text = (ROOT / "docs/api.md").read_text(encoding="utf-8")
    names = set(re.findall(r"\brailradio(?:\.[A-Za-z_]\w*)+", text))
    assert len(names) > 10
    missing = sorted(n for n in names if not _resolves(n))
    assert not missing, missing
