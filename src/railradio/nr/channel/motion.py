"""The geometry of every link while one SS burst is on the air (the train moves ≈ 0.26 m).

The production synthesizer (:class:`railradio.nr.synthesis.synthesizer.Synthesizer`) holds each link's
geometry at the epoch instant t0 over the whole ≈ 2 ms burst: the bulk delay τ0, a constant
LOS Doppler f_D cos α (a carrier phase linear in time) and the beam gains toward the train's
position at t0. :class:`BurstMotion` gives the same quantities at any instant of the burst
from the train's motion x(t) = x0 + v (t - t0) + a (t - t0)²/2, so that the exact reference
(:mod:`railradio.nr.synthesis.reference`) and the fast path with that shortcut switched off can use
them:

* τ(t) = d(t)/c, the 3-D distance at the receive instant over c (static transmitter: the
  wave received at t left the RRH at t - τ(t));
* the LOS carrier phase φ(t) = φ_lin(t) - 2π [d(t) - d0 - ḋ0 (t - t0)]/λ, where
  φ_lin(t) = 2π f_los t + φ0 is the production's linear phase (f_los = -ḋ0/λ), so the two
  agree to first order in t - t0 and differ by the curvature of d(t) (the Doppler's change
  while the train passes an RRH);
* the amplitude gain of every beam toward the train's position at t.

Path loss and shadowing stay at their t0 values: over 0.26 m the 3-D distance changes by at
most 0.26 m, ≤ 0.14 dB at the nearest approach (16.8 m), and the shadowing field is defined
on a 1 m grid.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.channel.antenna import RrhArray
from railradio.nr.channel.geometry import Deployment


@dataclass(frozen=True)
class BurstMotion:
    """Link geometry as a function of time during one burst.

    Parameters
    ----------
    deployment, rrh_array
        The RRHs and their beams.
    link_rrh
        [links] the RRH of each link.
    panel_x_m
        [links] along-track offset of each link's receiving panel from the train's
        reference point [m].
    x0_m, v_m_s, a_m_s2
        The train's reference position [m], speed [m/s] and acceleration [m/s²] at ``t0_s``.
    t0_s
        The epoch instant [s] at which the production holds the geometry.
    wavelength_m
        Carrier wavelength [m].
    """

    deployment: Deployment
    rrh_array: RrhArray
    link_rrh: NDArray[np.int64]
    panel_x_m: NDArray[np.float64]
    x0_m: float
    v_m_s: float
    a_m_s2: float
    t0_s: float
    wavelength_m: float

    def _times(self, t_s: NDArray) -> NDArray[np.float64]:
        t = np.asarray(t_s, float)
        return t[None, :] if t.ndim == 1 else t

    def position_m(self, t_s: NDArray) -> NDArray[np.float64]:
        """[links, T] along-track position of each link's receiving panel at times ``t_s``
        ([T], common to every link, or [links, T]) [m].

        Parameters
        ----------
        t_s : numpy.ndarray
            Times [s]: [T], common to every link, or [links, T].

        Returns
        -------
        numpy.ndarray
            [links, T] along-track positions of the panels [m].
        """
        dt = self._times(t_s) - self.t0_s
        x = self.x0_m + self.v_m_s * dt + 0.5 * self.a_m_s2 * dt**2
        return np.asarray(self.panel_x_m, float)[:, None] + x

    def distance_m(self, t_s: NDArray) -> NDArray[np.float64]:
        """[links, T] 3-D link distance [m].

        Parameters
        ----------
        t_s : numpy.ndarray
            Times [s]: [T], common to every link, or [links, T].

        Returns
        -------
        numpy.ndarray
            [links, T] 3-D distance from each link's RRH to its panel [m].
        """
        return self.deployment.distance_3d_m(self.position_m(t_s), np.asarray(self.link_rrh)[:, None])

    def delay_s(self, t_s: NDArray) -> NDArray[np.float64]:
        """[links, T] bulk delay τ(t) = d(t)/c [s].

        Parameters
        ----------
        t_s : numpy.ndarray
            Times [s]: [T], common to every link, or [links, T].

        Returns
        -------
        numpy.ndarray
            [links, T] bulk delays [s].
        """
        return self.distance_m(t_s) / SPEED_OF_LIGHT_M_S

    def phase_excess_rad(self, t_s: NDArray) -> NDArray[np.float64]:
        """[links, T] the exact LOS carrier phase minus the production's linear one,
        -2π [d(t) - d0 - ḋ0 (t - t0)]/λ [rad] (0 at t0 and of second order in t - t0).

        Parameters
        ----------
        t_s : numpy.ndarray
            Times [s]: [T], common to every link, or [links, T].

        Returns
        -------
        numpy.ndarray
            [links, T] phase excess [rad].
        """
        t = self._times(t_s)
        d = self.distance_m(t)
        d0 = self.distance_m(np.array([self.t0_s]))
        # ḋ0 = v (x_p - x_k)/d0 at t0 (the production's f_los = -ḋ0/λ)
        dx0 = self.position_m(np.array([self.t0_s])) - self.deployment.x_m[np.asarray(self.link_rrh)][:, None]
        d_dot0 = self.v_m_s * dx0 / d0
        lin = d0 + d_dot0 * (t - self.t0_s)
        return -2 * np.pi * (d - lin) / self.wavelength_m

    def beam_amp(self, t_s: NDArray) -> NDArray[np.float64]:
        """[links, T, n_beams] amplitude gain of every beam toward the panel at ``t_s``.

        Parameters
        ----------
        t_s : numpy.ndarray
            Times [s]: [T], common to every link, or [links, T].

        Returns
        -------
        numpy.ndarray
            [links, T, n_beams] linear amplitude gains [1] (10^(G/20), G the beam gain [dBi]
            toward the panel's AOD).
        """
        x = self.position_m(t_s)
        aod = self.deployment.aod_rad(x, np.asarray(self.link_rrh)[:, None])
        return 10 ** (self.rrh_array.beam_gains_db(aod) / 20)


def burst_motion(lb, scn, x0_m: float, v_m_s: float, a_m_s2: float, t0_s: float) -> BurstMotion:
    """The :class:`BurstMotion` of the links of a link budget ``lb``
    (:class:`railradio.nr.channel.link.LinkBudget`) in scenario ``scn``.

    Parameters
    ----------
    lb : LinkBudget
        The epoch's link budget (one link per RRH in ``rrh`` or per RRH and panel in
        ``link_rrh``, with the panels' offsets ``link_panel_x_m`` [m]).
    scn : Scenario
        The scenario (:class:`railradio.nr.engine.simulate.Scenario`): deployment, RRH beams and the
        carrier wavelength.
    x0_m : float
        The train's reference position at ``t0_s`` [m].
    v_m_s : float
        Its speed at ``t0_s`` [m/s].
    a_m_s2 : float
        Its acceleration [m/s²].
    t0_s : float
        The epoch instant [s].

    Returns
    -------
    BurstMotion
        The links' geometry over the burst (panel offsets 0 without separate panels).
    """
    rrh = lb.rrh if lb.link_rrh is None else lb.link_rrh
    panel = np.zeros(len(rrh)) if lb.link_panel_x_m is None else lb.link_panel_x_m
    return BurstMotion(
        scn.deployment,
        scn.rrh_array,
        np.asarray(rrh, np.int64),
        np.asarray(panel, float),
        float(x0_m),
        float(v_m_s),
        float(a_m_s2),
        float(t0_s),
        scn.radio.wavelength_m,
    )
