"""One figure style for the whole study, headless and deterministic.

:func:`figure` opens a figure in the package style (``data/railradio.mplstyle``, a
colour-blind-safe cycle); :func:`save` writes a vector PDF and a PNG beside it, atomically
and with fixed metadata so the same data give the same files.
"""

from __future__ import annotations

import os
from importlib.resources import files
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

STYLE = str(files("railradio") / "data" / "railradio.mplstyle")
plt.style.use(STYLE)  # every figure of the process (each workflow job is its own process)
BOUND_STYLE = {"color": "black", "linestyle": "--", "linewidth": 1.0}
"""Line style of physical-limit curves (CRLB/PEB), the same in every figure."""


def figure(**kwargs):
    """A new ``(fig, ax)`` in the package style (kwargs go to :func:`plt.subplots`)."""
    return plt.subplots(**kwargs)


def log_axis(ax, axis: str = "y") -> None:
    """Logarithmic ``axis`` with plain-number tick labels (1, 2, 5, 10, 20, ...)."""
    from matplotlib.ticker import FuncFormatter, LogLocator

    fmt = FuncFormatter(lambda v, _: f"{v:g}")
    target = ax.yaxis if axis == "y" else ax.xaxis
    (ax.set_yscale if axis == "y" else ax.set_xscale)("log")
    target.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    target.set_major_formatter(fmt)
    target.set_minor_formatter(FuncFormatter(lambda v, _: ""))


def save(fig, pdf_path: str | os.PathLike[str], png_path: str | os.PathLike[str] | None = None) -> None:
    """Save ``fig`` as PDF (and PNG) atomically with deterministic metadata, then close it."""
    from railradio.io import atomic_path

    pdf_path = Path(pdf_path)
    png_path = Path(png_path) if png_path is not None else pdf_path.with_suffix(".png")
    with atomic_path(pdf_path) as tmp:
        fig.savefig(
            tmp,
            format="pdf",
            metadata={"CreationDate": None, "ModDate": None, "Producer": None, "Creator": "railradio"},
        )
    with atomic_path(png_path) as tmp:
        fig.savefig(tmp, format="png", metadata={"Software": None})
    plt.close(fig)


def plot_rulegraph(dot: str, png: str, svg: str | None = None) -> None:
    """Draw Snakemake's ``--rulegraph`` (DOT text) without Graphviz: rules in layers by
    their longest path from the inputs, one colour per study (the name's prefix), edges
    from producer to consumer."""
    import re

    import matplotlib.pyplot as plt

    labels = dict(re.findall(r'^\s*(\d+)\[label = "([^"]+)"', dot, re.M))
    edges = [(a, b) for a, b in re.findall(r"^\s*(\d+) -> (\d+)", dot, re.M)]
    if not labels:
        raise ValueError("dot has no nodes (expected `snakemake --rulegraph` output)")
    layer = {n: 0 for n in labels}
    for _ in range(len(labels)):  # longest path from a source (the graph is acyclic)
        changed = False
        for a, b in edges:
            if layer[b] < layer[a] + 1:
                layer[b], changed = layer[a] + 1, True
        if not changed:
            break
    rows: dict[int, list[str]] = {}
    for n in sorted(labels, key=lambda n: labels[n]):
        rows.setdefault(layer[n], []).append(n)
    width = max(len(r) for r in rows.values())
    pos = {n: ((i + 0.5) * width / len(r), -lv) for lv, r in rows.items() for i, n in enumerate(r)}
    studies = sorted({labels[n].split("_")[0] for n in labels})
    colour = {s: f"C{i}" for i, s in enumerate(studies)}
    fig, ax = plt.subplots(figsize=(max(8.0, 1.6 * width), 0.9 * (len(rows) + 1)))
    for a, b in edges:
        ax.annotate(
            "", xy=pos[b], xytext=pos[a], arrowprops=dict(arrowstyle="->", color="0.6", lw=0.8, shrinkA=9, shrinkB=9)
        )
    for n, (x, y) in pos.items():
        ax.text(
            x,
            y,
            labels[n],
            ha="center",
            va="center",
            fontsize=7,
            bbox=dict(boxstyle="round,pad=0.3", fc="white", ec=colour[labels[n].split("_")[0]], lw=1.5),
        )
    ax.set_xlim(-0.2, width + 0.2)
    ax.set_ylim(-max(rows) - 0.6, 0.6)
    ax.axis("off")
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    if svg:
        fig.savefig(svg)
    plt.close(fig)
