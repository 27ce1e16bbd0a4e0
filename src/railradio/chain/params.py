"""Parameters of the chain study (config section ``chain``), checked with ValueError
naming the parameter."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

NR_FILTERS = ("ekf", "imm")
"""Causal trackers of the nr IMM files usable as position input (the RTS smoother is
non-causal: a handover decision cannot wait for future bursts)."""


def _num(name: str, value: Any, lo: float, hi: float, lo_open: bool = False) -> float:
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    if (value <= lo if lo_open else value < lo) or value > hi:
        raise ValueError(f"{name} must be in {'(' if lo_open else '['}{lo}, {hi}], got {value!r}")
    return float(value)


@dataclass(frozen=True)
class ChainParams:
    """The chain study's knobs.

    speed_kmh
        train speed of the chained handover run [km/h] (the seed's headline 350 km/h).
    sigmas_m
        Gauss–Markov position-error σ grid [m], ascending, starting at 0.
    gm_corr_s
        correlation time of the swept Gauss–Markov error [s] (the handover default, 1 s).
    nr_filters
        nr trackers whose along-track error is chained (``ekf``: the seed's EKF on the robust
        receiver's gated AOD+TOA; ``imm``).
    speed_halfwidth_kmh
        nr epochs used: true speed within ±this of ``speed_kmh`` [km/h].
    outage_drift_m_s
        dead-reckoning drift of the position during an nr outage (epoch without a fix) [m/s].
    n_blocks
        handover blocks (``runs_per_block`` crossings each) on the handover sweep's draws.
    """

    speed_kmh: float = 350.0
    sigmas_m: tuple[float, ...] = (0.0, 0.5, 1.0, 2.0, 3.0, 5.0, 7.5, 10.0, 15.0, 20.0)
    gm_corr_s: float = 1.0
    nr_filters: tuple[str, ...] = ("ekf",)
    speed_halfwidth_kmh: float = 50.0
    outage_drift_m_s: float = 0.5
    n_blocks: int = 50

    def __post_init__(self) -> None:
        _num("speed_kmh", self.speed_kmh, 0.0, 600.0, lo_open=True)
        s = list(self.sigmas_m)
        if len(s) < 2:
            raise ValueError(f"sigmas_m must hold at least 2 values, got {s!r}")
        for v in s:
            _num("sigmas_m", v, 0.0, 1000.0)
        if any(b <= a for a, b in zip(s, s[1:], strict=False)):
            raise ValueError(f"sigmas_m must be strictly ascending, got {s!r}")
        _num("gm_corr_s", self.gm_corr_s, 0.0, 1e4, lo_open=True)
        for f in self.nr_filters:
            if f not in NR_FILTERS:
                raise ValueError(f"nr_filters must be a subset of {NR_FILTERS}, got {list(self.nr_filters)!r}")
        _num("speed_halfwidth_kmh", self.speed_halfwidth_kmh, 0.0, 1000.0, lo_open=True)
        _num("outage_drift_m_s", self.outage_drift_m_s, 0.0, 100.0)
        if not isinstance(self.n_blocks, int) or isinstance(self.n_blocks, bool) or self.n_blocks < 1:
            raise ValueError(f"n_blocks must be an integer >= 1, got {self.n_blocks!r}")

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["sigmas_m"], d["nr_filters"] = list(self.sigmas_m), list(self.nr_filters)
        return d


WORKFLOW_KEYS = ("n_batches", "figure_max_sigma_m")
"""Keys of the ``chain`` config section that steer the workflow, not the simulation."""


def params_from_config(cfg: dict[str, Any]) -> ChainParams:
    """:class:`ChainParams` from the config's ``chain`` section (workflow keys ignored,
    unknown keys rejected)."""
    kw = {k: v for k, v in cfg.items() if k not in WORKFLOW_KEYS}
    extra = set(kw) - set(ChainParams.__dataclass_fields__)
    if extra:
        raise ValueError(f"unknown chain parameter(s) {sorted(extra)}")
    for k in ("sigmas_m", "nr_filters"):
        if k in kw:
            kw[k] = tuple(kw[k])
    return ChainParams(**kw)
