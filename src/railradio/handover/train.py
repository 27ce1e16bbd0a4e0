"""The train's motion, its nodes and its position input (docs/model/handover.md §1, §6).

The head starts at the serving RRH (x = 0) at t = 0 [source: "the train starts at the
serving eNB and moves to the target eNB"] and moves at constant speed v; node i
(0-based, node 0 = head) is i·s behind it.  Samples every T_m until the last node reaches
the target RRH.  The GNSS/INS error is one process for the whole train (one receiver; the
nodes' positions follow from the known node offsets).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from railradio.handover.params import Scenario, check_speed
from railradio.handover.radio import ShadowGrid, ar1_coefficient, ar1_process

FIELD_MARGIN_BEHIND_M = 50.0
FIELD_MARGIN_AHEAD_M = 250.0
"""Span of the shadowing grid beyond the nodes' sampled positions [m] (room for retries;
independent of the speed, so every speed sees the same field: common random numbers)."""


@dataclass(frozen=True)
class Kinematics:
    """Sample times and true node positions of one crossing at one speed."""

    speed_m_s: float
    period_s: float
    n_samples: int
    node_offsets_m: np.ndarray  # [N], node i is node_offsets_m[i] behind the head
    grid: ShadowGrid

    @property
    def t_s(self) -> np.ndarray:
        """Sample times [s], [K]."""
        return self.period_s * np.arange(self.n_samples)

    @property
    def x_head_m(self) -> np.ndarray:
        """True head position at the samples [m], [K]."""
        return self.speed_m_s * self.t_s

    @property
    def x_nodes_m(self) -> np.ndarray:
        """True node positions [m], [N, K]."""
        return self.x_head_m[None, :] - self.node_offsets_m[:, None]


def kinematics(scn: Scenario, speed_kmh: float) -> Kinematics:
    """:class:`Kinematics` of a crossing at ``speed_kmh``.

    Parameters
    ----------
    scn : Scenario
        The scenario (cell spacing, measurement period T_m, nodes and their spacing,
        shadowing grid step).
    speed_kmh : float
        Train speed [km/h], 1 ≤ v ≤ 1000.

    Returns
    -------
    Kinematics
        ``speed_m_s`` [m/s], ``period_s`` = T_m [s], ``n_samples`` K (samples from t = 0 until
        the last node reaches the target RRH), ``node_offsets_m`` [m] [N] and the shadowing
        ``grid`` spanning the nodes' positions plus margins.

    Raises
    ------
    ValueError
        If ``speed_kmh`` is not a finite number in 1–1000 km/h.
    """
    v = check_speed(speed_kmh)
    tr, rd = scn.train, scn.radio
    train_length = tr.node_spacing_m * (tr.n_nodes - 1)
    t_end = (rd.x_target_m + train_length) / v
    n = int(math.floor(t_end / rd.meas_period_s + 1e-9)) + 1
    grid = ShadowGrid(
        rd.x_serving_m - train_length - FIELD_MARGIN_BEHIND_M,
        rd.x_target_m + train_length + FIELD_MARGIN_AHEAD_M,
        rd.shadow_grid_m,
    )
    return Kinematics(v, rd.meas_period_s, n, tr.node_spacing_m * np.arange(tr.n_nodes), grid)


def gnss_error_m(white: np.ndarray, scn: Scenario) -> np.ndarray:
    """Along-track GNSS/INS error [m] from standard normals [..., K].

    First-order Gauss–Markov (AR(1) at the sample period with φ = exp(−T_m/τ), stationary
    std σ), clipped at ±bound (the source's "error within 5 m").
    """
    tr = scn.train
    if tr.gnss_sigma_m == 0.0:
        return np.zeros(np.shape(white))
    phi = ar1_coefficient(scn.radio.meas_period_s, tr.gnss_corr_s)
    e = ar1_process(white, phi, tr.gnss_sigma_m)
    return np.clip(e, -tr.gnss_bound_m, tr.gnss_bound_m)
