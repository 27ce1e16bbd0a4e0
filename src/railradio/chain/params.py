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

    Parameters
    ----------
    speed_kmh : float, default 350.0
        train speed of the chained handover run [km/h] (the source's headline 350 km/h), in (0, 600].
    sigmas_m : tuple of float, default (0.0, 0.5, 1.0, 2.0, 3.0, 5.0, 7.5, 10.0, 15.0, 20.0)
        Gauss–Markov position-error σ grid [m], ascending, starting at 0.  At least 2 values,
        each in [0, 1000], strictly ascending.
    gm_corr_s : float, default 1.0
        correlation time of the swept Gauss–Markov error [s] (the handover default, 1 s), in
        (0, 1e4].
    nr_filters : tuple of str, default ("ekf",)
        nr trackers whose along-track error is chained (``ekf``: the source's EKF on the robust
        receiver's gated AOD+TOA; ``imm``), a subset of :data:`NR_FILTERS`.
    speed_halfwidth_kmh : float, default 50.0
        nr epochs used: true speed within ±this of ``speed_kmh`` [km/h], in (0, 1000].
    outage_drift_m_s : float, default 0.5
        dead-reckoning drift of the position during an nr outage (epoch without a fix) [m/s],
        in [0, 100].
    n_blocks : int, default 50
        handover blocks (``runs_per_block`` crossings each) on the handover sweep's draws, >= 1.

    Raises
    ------
    ValueError
        If a parameter is not a finite number (an integer for ``n_blocks``) in its range,
        ``sigmas_m`` is not strictly ascending or has fewer than 2 values, or ``nr_filters``
        names an unknown tracker; the message names the parameter.
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
        """The parameters as a plain dict (tuples as lists), for the datasets' provenance.

        Returns
        -------
        dict
            Field name -> value, in the units of the field names (km/h, m, s, m/s).
        """
        d = asdict(self)
        d["sigmas_m"], d["nr_filters"] = list(self.sigmas_m), list(self.nr_filters)
        return d


WORKFLOW_KEYS = ("n_batches", "figure_max_sigma_m")
"""Keys of the ``chain`` config section that steer the workflow, not the simulation."""


def params_from_config(cfg: dict[str, Any]) -> ChainParams:
    """:class:`ChainParams` from the config's ``chain`` section (workflow keys ignored,
    unknown keys rejected).

    Parameters
    ----------
    cfg : dict
        The config's ``chain`` section: fields of :class:`ChainParams` (units as named:
        ``speed_kmh`` [km/h], ``sigmas_m`` [m], ``gm_corr_s`` [s], ...; lists allowed for
        ``sigmas_m`` and ``nr_filters``) plus the workflow keys :data:`WORKFLOW_KEYS`
        (``n_batches``, ``figure_max_sigma_m``), which are ignored.

    Returns
    -------
    ChainParams
        The checked parameters; fields missing from ``cfg`` take their defaults.

    Raises
    ------
    ValueError
        If ``cfg`` holds an unknown key, or a value is out of the range :class:`ChainParams`
        checks.
    """
    kw = {k: v for k, v in cfg.items() if k not in WORKFLOW_KEYS}
    extra = set(kw) - set(ChainParams.__dataclass_fields__)
    if extra:
        raise ValueError(f"unknown chain parameter(s) {sorted(extra)}")
    for k in ("sigmas_m", "nr_filters"):
        if k in kw:
            kw[k] = tuple(kw[k])
    return ChainParams(**kw)
