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
