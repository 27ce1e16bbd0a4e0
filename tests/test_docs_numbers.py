"""The numbers the documentation quotes from key numbers are the keys' values.

A number is quoted from a key when the key's name, in backticks, stands right next to it:
``3.63 dB/km (`tunnel.rays.local_mean_slope_db_per_km.1500_5000`)``, ``(2.79 dB/km, `key`)``,
``(key `name`)`` after the number, or ``` `name` = 0.009 m ``` / ``` `name` (4.4 s) ``` after the
key (docs/testing.md). Every such number must equal the key's value (in paper/numbers.json
or one of the nr records) to the digits it prints, in the key's unit or one a power of ten
(10^±3, 10^±6, 10^9) or a percentage away. A text that quotes a key's number otherwise is
not checked, so write new quotes this way.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
KEY_FILES = ("numbers", "map_numbers", "cases_numbers", "fidelity_numbers")
DOCS = (
    sorted((ROOT / "docs" / "model").glob("*.md"))
    + [p for p in sorted((ROOT / "docs").glob("*.md")) if p.name != "keys.md"]
    + [ROOT / "README.md", ROOT / "config" / "README.md"]
)
NUMBER = r"(?<![\w.−-])([−-]?\d[\d,]*(?:\.\d+)?)(?!\d|\.\d)"
BEFORE = re.compile(NUMBER + r"\s*[^\s(\d,;]{0,12}\s*(?:\(|\(keys? |, keys? )$")
INSIDE = re.compile(r"\(" + NUMBER + r"\s*[^\s(\d,;]{0,12},\s*$")  # (2.79 dB/km, `key`
AFTER = re.compile(r"\s*(?:\(|=|:)?\s*" + NUMBER)
SCALES = (1.0, 1e3, 1e-3, 1e6, 1e-6, 1e9, 100.0)


def _keys() -> dict[str, float]:
    out: dict[str, float] = {}
    for name in KEY_FILES:
        for k, v in json.loads((ROOT / "paper" / f"{name}.json").read_text()).items():
            v = v.get("value") if isinstance(v, dict) else v
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                out[k] = float(v)
    return out


def _agrees(text: str, value: float) -> bool:
    """``text`` (a printed number) equals ``value`` in some unit scale to its printed digits."""
    x = float(text.replace("−", "-").replace(",", ""))
    if x == 0:  # a quoted zero is exact and in the key's unit
        return value == 0
    digits = text.replace("−", "").replace("-", "").replace(",", "")
    if "." in digits:
        tol = 0.5 * 10.0 ** -len(digits.split(".")[1])
    else:  # an integer: half a unit of its last non-zero digit (2 300 may be 2 3xx rounded)
        tol = 0.5 * 10.0 ** (len(digits) - len(digits.rstrip("0")))
    return any(abs(x - value * scale) <= tol * (1 + 1e-9) for scale in SCALES)


def quotes(path: Path, keys: dict[str, float]) -> list[tuple[str, str, int]]:
    """(number as printed, key, line) for every number the file quotes from a key."""
    text = path.read_text()
    out = []
    for m in re.finditer(r"`([a-z][a-z0-9_.]+)`", text):
        key = m.group(1)
        if key not in keys:
            continue
        line = text.count("\n", 0, m.start()) + 1
        left = text[max(0, m.start() - 40) : m.start()]
        before = BEFORE.search(left) or INSIDE.search(left)
        if before:
            out.append((before.group(1), key, line))
        after = AFTER.match(text[m.end() : m.end() + 40])
        if after:
            out.append((after.group(1), key, line))
    return out


def test_quoted_key_numbers_are_current():
    keys = _keys()
    wrong, n = [], 0
    for path in DOCS:
        for number, key, line in quotes(path, keys):
            n += 1
            if not _agrees(number, keys[key]):
                wrong.append(f"{path.relative_to(ROOT)}:{line}: {number} quoted for {key} = {keys[key]:.6g}")
    assert not wrong, "\n".join(wrong)
    assert n >= 20  # the convention is in use


def test_the_checker_catches_a_stale_number(tmp_path):
    keys = {"nr.predict.pcrb_m.mean": 0.3631, "nr.bound.toa_crb_m.median": 0.00855}
    doc = tmp_path / "doc.md"
    doc.write_text(
        "PCRB 0.40 m (`nr.predict.pcrb_m.mean`); `nr.bound.toa_crb_m.median` = 0.009 m; "
        "36.3 % (`nr.predict.pcrb_m.mean`); EH11 (`nr.predict.pcrb_m.mean`); `nr.bound.toa_crb_m.median` = 0.009."
    )
    found = quotes(doc, keys)
    assert [(q[0], q[1]) for q in found] == [
        ("0.40", "nr.predict.pcrb_m.mean"),
        ("0.009", "nr.bound.toa_crb_m.median"),
        ("36.3", "nr.predict.pcrb_m.mean"),
        ("0.009", "nr.bound.toa_crb_m.median"),
    ]
    assert [_agrees(q[0], keys[q[1]]) for q in found] == [False, True, True, True]


@pytest.mark.parametrize(
    ("text", "value", "ok"),
    [
        ("3.63", 3.6332, True),
        ("3.64", 3.6332, False),
        ("948", 947.6, True),
        ("174", 173.42, False),
        ("0", 1.0, False),
        ("0", 0.0, True),
        ("2300", 2306.0, True),
        ("−19", -0.194, True),
    ],
)
def test_agreement_is_to_the_printed_digits(text, value, ok):
    assert _agrees(text, value) is ok
