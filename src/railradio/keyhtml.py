"""Every key number in one sortable, filterable page (the report's "key numbers, filterable"
table): the tidy table of :mod:`railradio.keytable` in DataTables, so a reader can search all
keys, filter each column (e.g. study ``nr``, verdict ``fails``) and sort by any of them.

DataTables comes from the ITables package, which ships it as one ES-module bundle with its
style sheet. The page carries the bundle, the style sheet and the rows gzip-compressed and
base64-encoded, and unpacks them in the browser (``DecompressionStream``): it loads nothing
from the network, and it stays small (≈ 0.4 MB for 3 700 keys instead of ≈ 1.9 MB through
ITables' own HTML export), which matters because the Snakemake report embeds a result as a
``data:`` URL and Chromium refuses URLs over 2 MB.
"""

from __future__ import annotations

import base64
import gzip
import html
import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from railradio.keytable import COLUMNS, rows

PAGE_LENGTHS = (25, 100, 500, -1)
"""Rows per page the reader can choose (-1: all)."""

NUMERIC = ("value", "mc_stderr", "lost_frac", "source_value")
"""Columns shown as numbers (right-aligned, sorted as numbers)."""

_LOADER = """
async function unpack(b64) {
  const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("gzip"));
  return await new Response(stream).text();
}
const [js, css, text] = await Promise.all([unpack(LIB_JS), unpack(LIB_CSS), unpack(ROWS)]);
const style = document.createElement("style");
style.textContent = css;
document.head.appendChild(style);
const url = URL.createObjectURL(new Blob([js], { type: "text/javascript" }));
const { default: DataTable } = await import(url);
URL.revokeObjectURL(url);
const { columns, numeric, rows, pageLength, lengthMenu } = JSON.parse(text);
const table = document.getElementById("keys");
const cells = (tag) => "<tr>" + columns.map((c) => `<${tag}>${c}</${tag}>`).join("") + "</tr>";
table.innerHTML = `<thead>${cells("th")}</thead><tfoot>${cells("th")}</tfoot>`;
table.querySelectorAll("tfoot th").forEach((th) => {
  const input = document.createElement("input");
  input.type = "search";
  input.placeholder = th.textContent;
  input.size = 8;
  th.replaceChildren(input);
});
const dt = new DataTable(table, {
  data: rows,
  columns: columns.map((c) => ({
    title: c,
    render: DataTable.render.text(),
    type: numeric.includes(c) ? "num" : "string",
    className: numeric.includes(c) ? "dt-right" : "",
  })),
  pageLength,
  lengthMenu,
  order: [],
});
dt.columns().every(function () {
  const column = this;
  const input = column.footer().querySelector("input");
  input.addEventListener("input", () => {
    if (column.search() !== input.value) column.search(input.value).draw();
  });
});
document.body.dataset.ready = "true";
"""
"""The page's script: unpack the bundle, the style sheet and the rows, then build the table
(one filter box per column in the footer; ``body[data-ready]`` once it is drawn)."""


def _shown(v: Any, digits: int | None) -> str:
    """A value as the table shows it: at least 4 significant digits (more when the key prints
    more), a whole number as one, no exponent in [1e-4, 1e7), an absent value empty (DataTables
    still sorts the column as numbers)."""
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return ""
    v, sig = float(v), max(digits or 0, 4)
    if v == int(v) and abs(v) < 1e7:
        return str(int(v))
    mag = math.floor(math.log10(abs(v)))
    return f"{v:.{max(sig - 1 - mag, 0)}f}" if -4 <= mag < 7 else f"{v:.{sig - 1}e}"


def _packed(data: bytes) -> str:
    """``data`` gzip-compressed (mtime 0: the same bytes give the same page) and base64-encoded."""
    return base64.b64encode(gzip.compress(data, compresslevel=9, mtime=0)).decode("ascii")


def table_rows(numbers: Mapping[str, Mapping[str, Any]]) -> list[list[str]]:
    """The rows the page shows: :data:`railradio.keytable.COLUMNS` of every key, sorted by key,
    each value as text (:data:`NUMERIC` columns to at least 4 significant digits, the source's
    value as it prints it)."""
    out = []
    for r in rows(numbers):
        digits = numbers[r["key"]].get("digits")
        shown = {c: _shown(r[c], digits) if c in NUMERIC else ("" if r[c] is None else str(r[c])) for c in COLUMNS}
        if r["source_value"] is not None:  # as the source prints it
            shown["source_value"] = f"{r['source_value']:g}"
        out.append([shown[c] for c in COLUMNS])
    return out


def unpack_rows(page: str) -> list[list[str]]:
    """The rows a page of :func:`filterable_table` carries (what the browser unpacks).

    Parameters
    ----------
    page : str
        The page's text.

    Returns
    -------
    list of list of str
        The rows, in :data:`railradio.keytable.COLUMNS` order.

    Raises
    ------
    ValueError
        When the page carries no rows.
    """
    start = page.find('const ROWS = "')
    if start < 0:
        raise ValueError("page carries no key-number rows (no ROWS constant)")
    start += len('const ROWS = "')
    b64 = page[start : page.index('"', start)]
    return json.loads(gzip.decompress(base64.b64decode(b64)))["rows"]


def filterable_table(numbers: Mapping[str, Mapping[str, Any]], title: str = "Key numbers") -> str:
    """A standalone HTML page with every key number in a sortable, filterable table.

    Parameters
    ----------
    numbers : mapping
        Key name -> key-number entry (``value``, ``unit``, ``mc_stderr``, ``source_value``,
        ``source_relation``, ``description``, optional ``digits`` and ``lost_frac``).
    title : str
        The page's title and heading.

    Returns
    -------
    str
        The page (UTF-8 text): a global search box, one filter box per column, sorting by
        any column; the columns of :data:`railradio.keytable.COLUMNS`, text shown as text.

    Raises
    ------
    ValueError
        When ``numbers`` is empty.
    """
    from itables.options import dt_bundle

    if not numbers:
        raise ValueError("numbers must hold at least one key number")
    bundle = Path(dt_bundle)
    data = {
        "columns": list(COLUMNS),
        "numeric": list(NUMERIC),
        "rows": table_rows(numbers),
        "pageLength": PAGE_LENGTHS[1],
        "lengthMenu": list(PAGE_LENGTHS),
    }
    consts = {
        "LIB_JS": _packed(bundle.read_bytes()),
        "LIB_CSS": _packed(bundle.with_suffix(".css").read_bytes()),
        "ROWS": _packed(json.dumps(data, ensure_ascii=False, separators=(",", ":")).encode("utf-8")),
    }
    esc = html.escape(title)
    return (
        "<!DOCTYPE html>\n<html lang='en'>\n<head>\n<meta charset='utf-8'>\n"
        f"<title>{esc}</title>\n</head>\n<body>\n<h1>{esc}</h1>\n"
        f"<p>{len(numbers)} keys. Type in the search box to find keys anywhere; type in a column's box "
        "below the table to filter that column (e.g. <code>nr</code> under study, <code>fails</code> "
        "under verdict); click a column's header to sort. The verdict rule: "
        '<code>config/README.md</code>, "verdicts"; every key also in '
        "<code>results/key_numbers.csv</code>.</p>\n"
        "<table id='keys' class='display compact' style='width:100%'></table>\n"
        "<noscript>The table needs JavaScript; every key is in results/key_numbers.csv.</noscript>\n"
        "<script type='module'>\n"
        + "".join(f'const {name} = "{value}";\n' for name, value in consts.items())
        + _LOADER
        + "</script>\n</body>\n</html>\n"
    )
