"""Antenna element and ULA beam patterns (source eq. 1; TR 38.901 Table 7.3-1).

Azimuth-only (horizontal cut, θ = 90°): the elevation of every link is below 30° at
d2D ≥ 15 m and the vertical pattern is not modelled [ours, stated].
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

ELEMENT_MAX_GAIN_DBI = 8.0  # TR 38.901 Table 7.3-1
ELEMENT_HPBW_DEG = 65.0
ELEMENT_FRONT_BACK_DB = 30.0
ARRAY_NULL_FLOOR = 1e-3
"""Array-factor floor (-30 dB): ideal nulls are filled in real arrays [ours]."""


def wrap_rad(a: NDArray) -> NDArray:
    """Wrap angles to (-π, π].

    Parameters
    ----------
    a : float or numpy.ndarray
        Angles [rad], any shape.

    Returns
    -------
    numpy.ndarray
        The angles wrapped to (-π, π] [rad], the shape of ``a``.
    """
    return -((-np.asarray(a) + np.pi) % (2 * np.pi) - np.pi)


def element_gain_db(phi_rel_rad: NDArray) -> NDArray[np.float64]:
    """TR 38.901 element gain [dBi] at azimuth φ' from boresight:
    8 - min(12 (φ'/65°)², 30).

    Parameters
    ----------
    phi_rel_rad : float or numpy.ndarray
        Azimuth from the element's boresight [rad] (any angle: wrapped here), any shape.

    Returns
    -------
    numpy.ndarray
        Element gain [dBi], the shape of ``phi_rel_rad``.
    """
    phi_deg = np.degrees(wrap_rad(phi_rel_rad))
    return ELEMENT_MAX_GAIN_DBI - np.minimum(12.0 * (phi_deg / ELEMENT_HPBW_DEG) ** 2, ELEMENT_FRONT_BACK_DB)


def ula_gain(phi_rel_rad: NDArray, steer_rel_rad: NDArray, n_elements: int) -> NDArray[np.float64]:
    """Linear array gain of an N-element λ/2 ULA steered to ``steer_rel_rad`` (angles from the
    array broadside = panel boresight): |Σ_n e^{jπ n (sin φ - sin φ_s)}|² / N (peak N).

    Parameters
    ----------
    phi_rel_rad : float or numpy.ndarray
        Azimuth from broadside [rad]; broadcast against ``steer_rel_rad``.
    steer_rel_rad : float or numpy.ndarray
        Steering direction from broadside [rad].
    n_elements : int
        Number of elements N; >= 1.

    Returns
    -------
    numpy.ndarray
        Array-factor power gain [linear], floored at :data:`ARRAY_NULL_FLOOR`; the broadcast
        shape of the two angles.

    Raises
    ------
    ValueError
        When ``n_elements`` < 1.
    """
    if n_elements < 1:
        raise ValueError(f"n_elements must be >= 1, got {n_elements!r}")
    u = np.sin(np.asarray(phi_rel_rad, float)) - np.sin(np.asarray(steer_rel_rad, float))
    shape = u.shape
    u = u.reshape(-1)
    # Dirichlet kernel: |Σ_n e^{jπnu}|² = sin²(Nπu/2) / sin²(πu/2); near u ≡ 0 (mod 2), where
    # both sines vanish, the explicit sum
    den = np.sin(0.5 * np.pi * u)
    near = np.abs(den) < 1e-6
    af2 = np.square(np.sin(0.5 * np.pi * n_elements * u) / np.where(near, 1.0, den))
    if np.any(near):
        af2[near] = np.abs(np.exp(1j * np.pi * u[near][:, None] * np.arange(n_elements)).sum(axis=-1)) ** 2
    return np.maximum(af2 / n_elements, ARRAY_NULL_FLOOR).reshape(shape)


@dataclass(frozen=True)
class RrhArray:
    """An RRH's two panels and its SS-burst beams (source §4; docs/model/nr.md §1).

    Beam k points at -(k + 0.5)·180/n_beams degrees; beams of the first half on the
    -45° panel, the rest on the -135° panel [ours].
    """

    n_elements: int = 32
    n_beams: int = 64
    boresights_deg: tuple[float, float] = (-45.0, -135.0)

    @cached_property
    def beam_angles_rad(self) -> NDArray[np.float64]:
        """Pointing azimuth of every SS beam, -(k + 0.5)·180°/n_beams.

        Returns
        -------
        numpy.ndarray
            Beam azimuths from the +x axis [rad], in (-π, 0): [n_beams].
        """
        k = np.arange(self.n_beams)
        return -np.radians((k + 0.5) * 180.0 / self.n_beams)

    @cached_property
    def beam_panel(self) -> NDArray[np.int64]:
        """Panel of every SS beam: 0 (first boresight) for the first half, 1 for the rest.

        Returns
        -------
        numpy.ndarray of int64
            Panel index per beam: [n_beams].
        """
        return (np.arange(self.n_beams) >= self.n_beams // 2).astype(np.int64)

    def beam_gains_db(self, aod_rad: NDArray) -> NDArray[np.float64]:
        """Gain [dBi] of every beam toward ``aod_rad``: shape [..., n_beams].

        Parameters
        ----------
        aod_rad : float or numpy.ndarray
            Azimuth of departure toward the train [rad] (:meth:`Deployment.aod_rad
            <railradio.nr.channel.geometry.Deployment.aod_rad>`), shape [...].

        Returns
        -------
        numpy.ndarray
            Element plus array gain of each beam on its panel [dBi]: [..., n_beams].
        """
        aod = np.asarray(aod_rad)[..., None]
        bore = np.radians(np.asarray(self.boresights_deg))[self.beam_panel]
        phi_rel = wrap_rad(aod - bore)
        steer_rel = wrap_rad(self.beam_angles_rad - bore)
        af = ula_gain(phi_rel, np.broadcast_to(steer_rel, phi_rel.shape), self.n_elements)
        return element_gain_db(phi_rel) + 10 * np.log10(af)


@dataclass(frozen=True)
class TrainArray:
    """The train's two panels (head: boresight 0°, forward; tail: 180°, backward), beams
    fixed along the track [source]; their chains are summed (power gains add, noise of both
    chains) [ours].

    ``panel_x_m`` = (head, tail): the panels' along-track positions relative to the train's
    reference point [m], head >= 0 >= tail (the train runs toward +x). (0, 0), the default,
    co-locates them at the reference point, as the source's eq. 14 treats the train as a
    point; otherwise every RRH reaches each panel over its own path (:func:`link_budget`)
    and the tracker's measurement model carries the lever arm [ours, docs/model/nr.md §1].
    """

    n_elements: int = 8
    n_chains: int = 2
    panel_x_m: tuple[float, float] = (0.0, 0.0)

    BORESIGHTS_RAD = (0.0, np.pi)

    def __post_init__(self) -> None:
        head, tail = (float(v) for v in self.panel_x_m)
        if not (head >= 0.0 >= tail):
            raise ValueError(f"panel_x_m must be (head >= 0, tail <= 0), got {self.panel_x_m!r}")

    @property
    def co_located(self) -> bool:
        """Whether both panels sit at the train's reference point (``panel_x_m`` = (0, 0)).

        Returns
        -------
        bool
            True when both along-track offsets are 0.
        """
        return all(float(v) == 0.0 for v in self.panel_x_m)

    def panel_gain_db(self, aoa_rad: NDArray, panel: int) -> NDArray[np.float64]:
        """Receive gain [dBi] of one panel (0 head, 1 tail) toward azimuth ``aoa_rad``.

        Parameters
        ----------
        aoa_rad : float or numpy.ndarray
            Azimuth of arrival from the +x axis [rad], any shape.
        panel : int
            0 (head, boresight 0) or 1 (tail, boresight π).

        Returns
        -------
        numpy.ndarray
            Element plus broadside-array gain [dBi], the shape of ``aoa_rad``.
        """
        phi = wrap_rad(np.asarray(aoa_rad) - self.BORESIGHTS_RAD[panel])
        return element_gain_db(phi) + 10 * np.log10(ula_gain(phi, 0.0 * phi, self.n_elements))

    def gain_db(self, aoa_rad: NDArray) -> NDArray[np.float64]:
        """Total receive gain [dBi] toward azimuth ``aoa_rad`` (both panels, co-located).

        Parameters
        ----------
        aoa_rad : float or numpy.ndarray
            Azimuth of arrival from the +x axis [rad], any shape.

        Returns
        -------
        numpy.ndarray
            10 log10 of the sum of both panels' linear gains [dBi], the shape of ``aoa_rad``.
        """
        total = np.zeros(np.shape(aoa_rad))
        for panel in (0, 1):
            total = total + 10 ** (self.panel_gain_db(aoa_rad, panel) / 10)
        return 10 * np.log10(total)


def facing_panel(x_m: NDArray, rrh_x_m: NDArray, offset_m: float, panel_x_m: tuple[float, float]) -> NDArray[np.int64]:
    """The panel (0 head, 1 tail) that sees each RRH closer to its boresight: the one a
    receiver with the train's geometry expects to measure it (the tracker's rule) [ours].

    Parameters
    ----------
    x_m : float or numpy.ndarray
        Train reference positions along the track [m]; broadcast against ``rrh_x_m``.
    rrh_x_m : float or numpy.ndarray
        RRH positions along the track [m].
    offset_m : float
        RRH distance from the track [m].
    panel_x_m : tuple of float
        (head, tail) along-track panel offsets from the reference point [m].

    Returns
    -------
    numpy.ndarray of int64
        0 (head) or 1 (tail), the broadcast shape of ``x_m`` and ``rrh_x_m``.
    """
    x = np.asarray(x_m, float)
    rx = np.asarray(rrh_x_m, float)
    off_head = np.abs(np.arctan2(offset_m, rx - (x + panel_x_m[0])))  # from +x
    off_tail = np.abs(np.arctan2(offset_m, (x + panel_x_m[1]) - rx))  # from -x
    return (off_tail < off_head).astype(np.int64)
