"""The handover figures say what they draw: every ▼ (a share with none observed, drawn at
its 95 % upper bound) has a legend entry on its own panel."""

import numpy as np
import xarray as xr

from railradio import plotting
from railradio.handover import figures


def _summary() -> xr.Dataset:
    speeds = np.array([100.0, 300.0, 500.0])
    policies = ["joint", "a3", "a3_rail", "distance"]
    shape = (len(policies), len(speeds))
    data = {}
    for name, value in (("success", 0.98), ("too_late", 0.01), ("too_early", 0.01)):
        p = np.full(shape, value)
        if name != "success":
            p[2, 0] = 0.0  # none observed: drawn as ▼ at the upper bound
        data[name] = (("policy", "speed_kmh"), p)
        data[f"{name}_lo"] = (("policy", "speed_kmh"), np.maximum(p - 0.005, 0.0))
        data[f"{name}_hi"] = (("policy", "speed_kmh"), p + 0.005)
    data["interruption_ms_median"] = (("policy", "speed_kmh"), np.full(shape, 30.0))
    data["interruption_ms_p95"] = (("policy", "speed_kmh"), np.full(shape, 40.0))
    return xr.Dataset(data, coords={"policy": policies, "speed_kmh": speeds})


def test_every_upper_bound_marker_is_explained_on_its_panel(tmp_path, monkeypatch):
    saved = []
    monkeypatch.setattr(plotting, "save", lambda fig, *a, **k: saved.append(fig))
    figures.plot_stages_vs_speed(_summary(), tmp_path / "f.pdf", tmp_path / "f.png")
    (fig,) = saved
    panels_with_bounds = 0
    for ax in fig.axes:
        has_bound = any(line.get_marker() == "v" and len(line.get_xdata()) for line in ax.get_lines())
        if has_bound:
            panels_with_bounds += 1
            legend = ax.get_legend()
            assert legend is not None, ax.get_title()
            assert any(t.get_text().startswith("none observed") for t in legend.get_texts()), ax.get_title()
    assert panels_with_bounds == 2  # too late, too early
