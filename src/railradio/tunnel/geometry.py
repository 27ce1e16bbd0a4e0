"""Tunnel and leaky-cable geometry (source 003 §1, §2.1-2.2; docs/model/tunnel.md §1).

Coordinates [source 2.1]: x along the tunnel from the portal, y vertical from the tunnel
floor (the lowest point of the lining), z transverse from the centreline.  The circular
cross-section of diameter D has its centre at (y, z) = (D/2, 0); the rectangle of equal
area (the image method's tunnel) is a square of side D sqrt(pi)/2 with its floor at y = 0.

The leaky coaxial cable (LCX) radiates through slots every ``slot_spacing_m`` at
(x_i, 0.1 H, z_slot) [source 2.2.1].  Slot-chain model (docs/model/tunnel.md §1): every slot is an
isotropic radiator whose EIRP is set so that the along-cable mean of the incoherent
free-space sum of all slots, at distance d_ref from the cable, equals the cable's
specified coupling loss L_c(d_ref) = 85 + 10 log10(d_ref / 1 m) dB [source 2.2.2]:

    P_s = P_c - L_c(d_ref) + 10 log10(d_ref s / pi) + 20 log10(4 pi / lambda) - G_ref   (1)

(the mean over x of sum_i lambda^2 / ((4 pi)^2 (d_ref^2 + (x - x_i)^2)) is
lambda^2 / (16 pi d_ref s) for a long chain).  G_ref = 2.15 dBi is the gain of the
lambda/2 dipole with which IEC 61196-4 measures the coupling loss: the received power
P_c - L_c includes that gain, so the slot EIRP is G_ref below the isotropic-receiver value,
and the train antenna (0 dBi in this study) then reads P_c - L_c - G_ref at d_ref.  The
coupling loss is thereby used once, to
set the slot power; every ray then carries free-space spreading and wall reflections only,
never coupling loss *and* free-space loss (the source's eq. 2.4.1 applies both).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from railradio.constants import SPEED_OF_LIGHT_M_S

SHAPES = ("circle", "rect")


def _positive(name: str, value: float) -> float:
    value = float(value)
    if not value > 0.0 or not math.isfinite(value):
        raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    return value


def equal_area_side_m(diameter_m: float) -> float:
    """Side of the square with the area of a circle of diameter D: D sqrt(pi)/2 [m].

    Parameters
    ----------
    diameter_m : float
        Diameter D of the circle [m]; positive and finite.

    Returns
    -------
    float
        Side of the square of equal area [m].

    Raises
    ------
    ValueError
        When ``diameter_m`` is not a positive finite number.
    """
    return _positive("diameter_m", diameter_m) * math.sqrt(math.pi) / 2.0


@dataclass(frozen=True)
class Tunnel:
    """A straight tunnel, its LCX slot line and the train antenna's cross-section position.

    ``shape`` 'circle' is the true cross-section [source]; 'rect' the square of equal area
    [ours], in which the image method is exact.

    Parameters
    ----------
    length_m : float
        Tunnel length along x from the portal [m]; positive and finite.
    diameter_m : float
        Diameter D of the circular cross-section [m]; positive and finite ('rect': the
        square of the same area, side D sqrt(pi)/2).
    shape : {'circle', 'rect'}
        Cross-section (:data:`SHAPES`).
    slot_spacing_m : float
        Spacing of the LCX slots along x [m]; positive and finite.
    slot_height_frac : float
        Height of the slot line above the floor as a fraction of the cross-section's
        height H [1]; in (0, 1).
    slot_z_m : float
        Transverse position z of the slot line from the centreline [m].
    rx_y_m : float
        Height y of the train antenna above the floor (the lowest point of the lining) [m].
    rx_z_m : float
        Transverse position z of the train antenna from the centreline [m].

    Raises
    ------
    ValueError
        When ``shape`` is not in :data:`SHAPES`; when ``length_m``, ``diameter_m`` or
        ``slot_spacing_m`` is not a positive finite number; when ``slot_height_frac`` is not
        in (0, 1); when the slot line or the antenna lies outside the cross-section or
        within 5 cm of its wall.
    """

    length_m: float = 5000.0
    diameter_m: float = 8.5
    shape: str = "circle"
    slot_spacing_m: float = 20.0
    slot_height_frac: float = 0.1
    slot_z_m: float = 0.0
    rx_y_m: float = 4.0
    rx_z_m: float = 0.0

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise ValueError(f"shape must be one of {SHAPES}, got {self.shape!r}")
        for name in ("length_m", "diameter_m", "slot_spacing_m"):
            _positive(name, getattr(self, name))
        if not 0.0 < self.slot_height_frac < 1.0:
            raise ValueError(f"slot_height_frac must be in (0, 1), got {self.slot_height_frac!r}")
        for name, (y, z) in (("slot", self.slot_yz), ("rx", self.rx_yz)):
            if not self.inside(y, z, margin_m=0.05):
                raise ValueError(
                    f"{name} position (y={y}, z={z}) m lies outside the {self.shape} "
                    f"cross-section (or within 5 cm of the wall)"
                )

    @property
    def height_m(self) -> float:
        """Height H of the cross-section [m]."""
        return self.diameter_m if self.shape == "circle" else equal_area_side_m(self.diameter_m)

    @property
    def width_m(self) -> float:
        """Width W of the cross-section [m]."""
        return self.height_m

    @property
    def area_m2(self) -> float:
        """Area of the cross-section, pi D^2 / 4 (the same for both shapes) [m^2]."""
        return math.pi * self.diameter_m**2 / 4.0

    @property
    def slot_yz(self) -> tuple[float, float]:
        """(y, z) of the slot line: 10 % of the height [source 2.2.1]."""
        return (self.slot_height_frac * self.height_m, self.slot_z_m)

    @property
    def rx_yz(self) -> tuple[float, float]:
        """(y, z) of the train antenna in the cross-section [m]."""
        return (self.rx_y_m, self.rx_z_m)

    @property
    def cross_distance_m(self) -> float:
        """Distance between slot line and receiver within the cross-section [m]."""
        (ys, zs), (yr, zr) = self.slot_yz, self.rx_yz
        return math.hypot(yr - ys, zr - zs)

    def inside(self, y: float, z: float, margin_m: float = 0.0) -> bool:
        """Whether (y, z) lies inside the cross-section, at least ``margin_m`` from the wall.

        Parameters
        ----------
        y : float
            Height above the floor [m].
        z : float
            Transverse position from the centreline [m].
        margin_m : float
            Least distance from the wall [m].

        Returns
        -------
        bool
            True if the point is inside with that margin.
        """
        if self.shape == "circle":
            r = self.diameter_m / 2.0
            return math.hypot(y - r, z) <= r - margin_m
        h, w = self.height_m, self.width_m
        return margin_m <= y <= h - margin_m and abs(z) <= w / 2.0 - margin_m

    def wall_distance_m(self, y: float, z: float) -> float:
        """Distance from (y, z) to the nearest wall [m].

        Parameters
        ----------
        y : float
            Height above the floor [m].
        z : float
            Transverse position from the centreline [m].

        Returns
        -------
        float
            Distance to the nearest wall [m] (negative outside the cross-section).
        """
        if self.shape == "circle":
            r = self.diameter_m / 2.0
            return r - math.hypot(y - r, z)
        return min(y, self.height_m - y, self.width_m / 2.0 - abs(z))

    @property
    def slot_x_m(self) -> np.ndarray:
        """Slot positions x_i = i dx, i = 0 .. N-1 [source 2.2.1] [m]."""
        n = int(round(self.length_m / self.slot_spacing_m))
        return np.arange(n) * self.slot_spacing_m

    def with_shape(self, shape: str) -> Tunnel:
        """The same tunnel with another cross-section (slot at 10 % of *its* height).

        Parameters
        ----------
        shape : {'circle', 'rect'}
            The new cross-section.

        Returns
        -------
        Tunnel
            A copy with ``shape`` replaced.

        Raises
        ------
        ValueError
            As :class:`Tunnel`, e.g. when the slot line or antenna falls outside the new
            cross-section.
        """
        return Tunnel(
            self.length_m,
            self.diameter_m,
            shape,
            self.slot_spacing_m,
            self.slot_height_frac,
            self.slot_z_m,
            self.rx_y_m,
            self.rx_z_m,
        )


@dataclass(frozen=True)
class Cable:
    """The radiating cable: feed points, longitudinal loss, velocity factor, coupling loss.

    Parameters
    ----------
    frequency_hz : float
        Carrier frequency [Hz]; positive and finite.
    feed_power_dbm : float
        Power P_c fed into the cable at every feed point [dBm].
    feed_spacing_m : float
        Length of the cable section served by one feed (the feed sits in its middle) [m];
        positive and finite.
    loss_db_per_m : float
        Longitudinal loss alpha_L of the cable [dB/m]; >= 0.
    velocity_factor : float
        Propagation speed in the cable relative to c [1]; in (0, 1].
    coupling_loss_db : float
        Coupling loss L_c at 1 m from the cable [dB] (L_c(d) = L_c + 10 log10(d / 1 m)).
    coupling_ref_m : float
        Reference distance d_ref at which the slot chain is calibrated to L_c(d_ref) [m];
        positive and finite.
    coupling_ref_gain_dbi : float
        Gain G_ref of the reference dipole with which the coupling loss is measured [dBi].

    Raises
    ------
    ValueError
        When ``frequency_hz``, ``feed_spacing_m`` or ``coupling_ref_m`` is not a positive
        finite number, ``loss_db_per_m`` < 0, or ``velocity_factor`` is not in (0, 1].
    """

    frequency_hz: float = 900e6
    feed_power_dbm: float = 30.0
    feed_spacing_m: float = 1000.0
    loss_db_per_m: float = 0.025
    velocity_factor: float = 0.88
    coupling_loss_db: float = 85.0
    coupling_ref_m: float = 2.0
    coupling_ref_gain_dbi: float = 2.15

    def __post_init__(self) -> None:
        for name in ("frequency_hz", "feed_spacing_m", "coupling_ref_m"):
            _positive(name, getattr(self, name))
        if self.loss_db_per_m < 0:
            raise ValueError(f"loss_db_per_m must be >= 0, got {self.loss_db_per_m!r}")
        if not 0.0 < self.velocity_factor <= 1.0:
            raise ValueError(f"velocity_factor must be in (0, 1], got {self.velocity_factor!r}")

    @property
    def wavelength_m(self) -> float:
        """Free-space wavelength c / f [m]."""
        return SPEED_OF_LIGHT_M_S / self.frequency_hz

    def coupling_loss_at_db(self, d_m) -> np.ndarray:
        """L_c(d) = L_c + 10 log10(d / 1 m) [source 2.2.2] [dB].

        Parameters
        ----------
        d_m : float or array_like
            Distance from the cable [m]; positive.

        Returns
        -------
        numpy.ndarray
            Coupling loss at ``d_m`` [dB], the shape of ``d_m``.

        Raises
        ------
        ValueError
            When any distance is <= 0.
        """
        d = np.asarray(d_m, dtype=float)
        if np.any(d <= 0):
            raise ValueError("d_m must be positive")
        return self.coupling_loss_db + 10.0 * np.log10(d)

    def slot_eirp_offset_db(self, slot_spacing_m: float) -> float:
        """P_s - P_c of eq. (1): slot EIRP relative to the local cable power [dB]
        (calibrated for the IEC reference dipole of ``coupling_ref_gain_dbi``).

        Parameters
        ----------
        slot_spacing_m : float
            Slot spacing s of the chain [m].

        Returns
        -------
        float
            Slot EIRP minus the cable power at the slot [dB].
        """
        d = self.coupling_ref_m
        lam = self.wavelength_m
        return float(
            -self.coupling_loss_at_db(d)
            + 10.0 * math.log10(d * slot_spacing_m / math.pi)
            + 20.0 * math.log10(4.0 * math.pi / lam)
            - self.coupling_ref_gain_dbi
        )

    def feed_x_m(self, length_m: float) -> np.ndarray:
        """Feed/amplifier points: one in the middle of every ``feed_spacing_m`` section [ours].

        Parameters
        ----------
        length_m : float
            Length of the cable (the tunnel) [m].

        Returns
        -------
        numpy.ndarray
            Feed positions x along the tunnel [m] (at least one).
        """
        n = max(1, int(math.ceil(length_m / self.feed_spacing_m - 1e-9)))
        return (np.arange(n) + 0.5) * self.feed_spacing_m

    def nearest_feed_m(self, x_m, length_m: float) -> np.ndarray:
        """The feed point that powers the cable at x (its own section) [m].

        Parameters
        ----------
        x_m : float or array_like
            Positions along the cable [m].
        length_m : float
            Length of the cable (the tunnel) [m].

        Returns
        -------
        numpy.ndarray
            Position of the feed of each x's section [m] (sections beyond the ends clipped
            to the first or last feed), the shape of ``x_m``.
        """
        feeds = self.feed_x_m(length_m)
        idx = np.clip(np.floor(np.asarray(x_m, dtype=float) / self.feed_spacing_m).astype(int), 0, feeds.size - 1)
        return feeds[idx]

    def cable_distance_m(self, x_m, length_m: float) -> np.ndarray:
        """Cable length from the feeding point to x [m].

        Parameters
        ----------
        x_m : float or array_like
            Positions along the cable [m].
        length_m : float
            Length of the cable (the tunnel) [m].

        Returns
        -------
        numpy.ndarray
            |x - x_feed| [m], the shape of ``x_m``.
        """
        x = np.asarray(x_m, dtype=float)
        return np.abs(x - self.nearest_feed_m(x, length_m))

    def cable_power_dbm(self, x_m, length_m: float) -> np.ndarray:
        """Power in the cable at x: P_c - alpha_L |x - x_feed| [dBm].

        Parameters
        ----------
        x_m : float or array_like
            Positions along the cable [m].
        length_m : float
            Length of the cable (the tunnel) [m].

        Returns
        -------
        numpy.ndarray
            Cable power at ``x_m`` [dBm].
        """
        return self.feed_power_dbm - self.loss_db_per_m * self.cable_distance_m(x_m, length_m)

    def cable_delay_s(self, x_m, length_m: float) -> np.ndarray:
        """Delay from the feed to x along the cable, |x - x_feed| / (v c) [s].

        All feeds are driven simultaneously (equalized distribution) [ours].

        Parameters
        ----------
        x_m : float or array_like
            Positions along the cable [m].
        length_m : float
            Length of the cable (the tunnel) [m].

        Returns
        -------
        numpy.ndarray
            Delay from the feed to ``x_m`` along the cable [s].
        """
        return self.cable_distance_m(x_m, length_m) / (self.velocity_factor * SPEED_OF_LIGHT_M_S)
