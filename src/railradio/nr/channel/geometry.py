"""Trajectory and deployment of the nr study (source 000 §4, docs/model/nr.md §1).

Straight track on y = 0; RRHs every 500 m at y = +15 m, height 10 m; train antennas at
2.5 m. Every delay, path loss and the tracker's range model use the same 3-D distance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from railradio.nr.waveform.sequences import N_ID1_MAX, pci


@dataclass(frozen=True)
class Trajectory:
    """Piecewise-constant acceleration along +x, sampled every ``dt_s`` from rest at x0.

    Parameters
    ----------
    phases
        ((duration [s], acceleration [m/s²]), ...); the source's Fig. 3 default is
        (200, +0.5), (27.5, 0), (150, +0.2), (200, -0.65): 43.000 km in 577.5 s.
    dt_s
        Measurement interval [s] (source: 0.1 s).
    x0_m
        Start position [m].
    v0_m_s
        Start speed [m/s] (0: from rest, as the source's trajectory; a short run at speed
        otherwise).
    """

    phases: tuple[tuple[float, float], ...]
    dt_s: float = 0.1
    x0_m: float = 0.0
    v0_m_s: float = 0.0

    def __post_init__(self) -> None:
        if not self.phases:
            raise ValueError("phases must not be empty")
        for dur, _ in self.phases:
            if not dur > 0:
                raise ValueError(f"phase durations must be > 0 [s], got {dur!r}")
        if not self.dt_s > 0:
            raise ValueError(f"dt_s must be > 0, got {self.dt_s!r}")
        if not self.v0_m_s >= 0:
            raise ValueError(f"v0_m_s must be >= 0 [m/s], got {self.v0_m_s!r}")

    @property
    def duration_s(self) -> float:
        """Total duration of the phases.

        Returns
        -------
        float
            Sum of the phase durations [s].
        """
        return float(sum(d for d, _ in self.phases))

    @property
    def n_epochs(self) -> int:
        """Number of measurement epochs: floor(duration / dt).

        Returns
        -------
        int
            Epochs at 0, dt, ..., (n_epochs - 1)·dt.
        """
        return int(math.floor(self.duration_s / self.dt_s + 1e-9))

    def times_s(self) -> NDArray[np.float64]:
        """Epoch times from the start.

        Returns
        -------
        numpy.ndarray
            k·dt_s for k = 0 .. n_epochs - 1 [s]: [n_epochs].
        """
        return np.arange(self.n_epochs) * self.dt_s

    def state(self, t_s: NDArray[np.float64]) -> tuple[NDArray, NDArray, NDArray]:
        """Exact position [m], speed [m/s] and acceleration [m/s²] at times ``t_s``.

        Times after the last phase continue its acceleration; times before 0 give x0_m and
        zero speed and acceleration.

        Parameters
        ----------
        t_s : numpy.ndarray
            Times from the start [s], any shape.

        Returns
        -------
        tuple of numpy.ndarray
            (x [m], v [m/s], a [m/s²]), each the shape of ``t_s``.
        """
        t = np.asarray(t_s, dtype=float)
        x = np.full_like(t, self.x0_m)
        v = np.zeros_like(t)
        a = np.zeros_like(t)
        t0, x_start, v_start = 0.0, self.x0_m, self.v0_m_s
        for i, (dur, acc) in enumerate(self.phases):
            last = i == len(self.phases) - 1
            sel = (t >= t0) & ((t < t0 + dur) | last)
            tau = t[sel] - t0
            x[sel] = x_start + v_start * tau + 0.5 * acc * tau**2
            v[sel] = v_start + acc * tau
            a[sel] = acc
            x_start += v_start * dur + 0.5 * acc * dur**2
            v_start += acc * dur
            t0 += dur
        return x, v, a


@dataclass(frozen=True)
class Deployment:
    """RRHs along the track and their cell IDs.

    Parameters
    ----------
    track_length_m
        Track length [m] (source: 43 km); RRHs at 0, spacing, 2·spacing, ... ≤ length.
    spacing_m, offset_m
        RRH spacing along and distance from the track [m] (source: 500 m, 15 m).
    h_bs_m, h_ut_m
        RRH and train antenna heights [m] [ours: 10 m, 2.5 m].
    """

    track_length_m: float = 43_000.0
    spacing_m: float = 500.0
    offset_m: float = 15.0
    h_bs_m: float = 10.0
    h_ut_m: float = 2.5

    def __post_init__(self) -> None:
        for name in ("track_length_m", "spacing_m", "offset_m", "h_bs_m", "h_ut_m"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")

    @property
    def n_rrh(self) -> int:
        """Number of RRHs: those at 0, spacing, 2·spacing, ... ≤ track length.

        Returns
        -------
        int
            floor(track_length_m / spacing_m) + 1.
        """
        return int(math.floor(self.track_length_m / self.spacing_m + 1e-9)) + 1

    @property
    def x_m(self) -> NDArray[np.float64]:
        """RRH positions along the track [m].

        Returns
        -------
        numpy.ndarray
            k·spacing_m [m]: [n_rrh].
        """
        return np.arange(self.n_rrh) * self.spacing_m

    def n_id(self) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """(N_ID1, N_ID2) per RRH: N_ID2 = k mod 3 (adjacent RRHs always differ),
        N_ID1 = (k div 3) mod 336, so PCI = k: unique up to 1008 RRHs [source rules].

        Returns
        -------
        tuple of numpy.ndarray of int64
            (N_ID1, N_ID2), each [n_rrh].
        """
        k = np.arange(self.n_rrh)
        return (k // 3) % (N_ID1_MAX + 1), k % 3

    def pci(self) -> NDArray[np.int64]:
        """Physical cell ID 3 N_ID1 + N_ID2 of every RRH (see :meth:`n_id`).

        Returns
        -------
        numpy.ndarray of int64
            PCI per RRH: [n_rrh].
        """
        n1, n2 = self.n_id()
        return pci(n1, n2)

    def distance_3d_m(self, x_m: NDArray, rrh: NDArray) -> NDArray[np.float64]:
        """3-D distance [m] between a train at (x, 0, h_UT) and RRH ``rrh`` at (x_k, offset, h_BS).

        Parameters
        ----------
        x_m : float or numpy.ndarray
            Train antenna positions along the track [m]; broadcast against ``rrh``.
        rrh : int or numpy.ndarray of int
            RRH indices k (into the RRH positions ``self.x_m``).

        Returns
        -------
        numpy.ndarray
            3-D distances [m], the broadcast shape of ``x_m`` and ``rrh``.
        """
        dx = np.asarray(x_m) - self.x_m[np.asarray(rrh)]
        return np.sqrt(dx**2 + self.offset_m**2 + (self.h_bs_m - self.h_ut_m) ** 2)

    def distance_2d_m(self, x_m: NDArray, rrh: NDArray) -> NDArray[np.float64]:
        """Horizontal (2-D) distance [m] between a train at (x, 0) and RRH ``rrh`` at (x_k, offset).

        Parameters
        ----------
        x_m : float or numpy.ndarray
            Train antenna positions along the track [m]; broadcast against ``rrh``.
        rrh : int or numpy.ndarray of int
            RRH indices k (into the RRH positions ``self.x_m``).

        Returns
        -------
        numpy.ndarray
            2-D distances [m], the broadcast shape of ``x_m`` and ``rrh``.
        """
        dx = np.asarray(x_m) - self.x_m[np.asarray(rrh)]
        return np.hypot(dx, self.offset_m)

    def aod_rad(self, x_m: NDArray, rrh: NDArray) -> NDArray[np.float64]:
        """Azimuth of departure at the RRH toward the train, atan2(0 - y_k, x - x_k) ∈ (-π, 0).

        Parameters
        ----------
        x_m : float or numpy.ndarray
            Train antenna positions along the track [m]; broadcast against ``rrh``.
        rrh : int or numpy.ndarray of int
            RRH indices k (into the RRH positions ``self.x_m``).

        Returns
        -------
        numpy.ndarray
            AOD from the +x axis [rad], the broadcast shape of ``x_m`` and ``rrh``.
        """
        dx = np.asarray(x_m) - self.x_m[np.asarray(rrh)]
        return np.arctan2(-self.offset_m * np.ones_like(dx), dx)

    def aoa_rad(self, x_m: NDArray, rrh: NDArray) -> NDArray[np.float64]:
        """Azimuth of arrival at the train from the RRH, atan2(y_k, x_k - x) ∈ (0, π).

        Parameters
        ----------
        x_m : float or numpy.ndarray
            Train antenna positions along the track [m]; broadcast against ``rrh``.
        rrh : int or numpy.ndarray of int
            RRH indices k (into the RRH positions ``self.x_m``).

        Returns
        -------
        numpy.ndarray
            AOA from the +x axis [rad], the broadcast shape of ``x_m`` and ``rrh``.
        """
        dx = self.x_m[np.asarray(rrh)] - np.asarray(x_m)
        return np.arctan2(self.offset_m * np.ones_like(dx), dx)

    def nearest(self, x_m: float, n: int) -> NDArray[np.int64]:
        """Indices of the ``n`` RRHs nearest to track position ``x_m`` (nearest first).

        Parameters
        ----------
        x_m : float
            Position along the track [m].
        n : int
            Number of RRHs.

        Returns
        -------
        numpy.ndarray of int64
            RRH indices by along-track distance (ties: lower index first): [min(n, n_rrh)].
        """
        order = np.argsort(np.abs(self.x_m - x_m), kind="stable")
        return order[:n]
