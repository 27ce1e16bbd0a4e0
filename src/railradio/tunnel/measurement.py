"""The receivers' measurement model and the place's random fields along the tunnel: per-slot
log-normal shadowing and delay error (docs/model/tunnel.md §3)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

DELAY_ERRORS = ("white", "ar1", "slot_bias")


@dataclass(frozen=True)
class MeasurementModel:
    """The receivers' measurement model (docs/model/tunnel.md §3).

    Parameters
    ----------
    shadow_sigma_db : float
        Standard deviation of the per-slot log-normal shadowing [dB]; >= 0.
    shadow_corr_m : float
        Correlation distance of the shadowing along the tunnel [m]; positive.
    delay_sigma_s : float
        Standard deviation of the separable receiver's per-slot delay error [s]; positive.
    n_slots : int
        Number of the strongest measured slots used per fix (separable receiver); >= 3.
    window_m : float
        Half-width of the window of slots around the receiver that are considered [m];
        positive.
    bandwidth_hz : float
        Bandwidth B of the wideband receiver [Hz]; positive.
    n_tones : int
        Number of sounding tones across B (wideband receiver).
    noise_figure_db : float
        Receiver noise figure F [dB] (thermal noise kT F B of the wideband receiver).
    delay_error : {'white', 'ar1', 'slot_bias'}
        Time structure of the delay error (:data:`DELAY_ERRORS`; simulate module docstring).
    delay_corr_m : float
        Correlation distance of the ``ar1`` delay error along the track [m]; positive.

    Raises
    ------
    ValueError
        When ``delay_error`` is unknown, ``n_slots`` < 3, ``shadow_sigma_db`` < 0, or
        ``delay_corr_m``, ``shadow_corr_m``, ``delay_sigma_s``, ``window_m`` or
        ``bandwidth_hz`` is not positive.
    """

    shadow_sigma_db: float = 4.0
    shadow_corr_m: float = 10.0
    delay_sigma_s: float = 20e-9
    n_slots: int = 8
    window_m: float = 200.0
    bandwidth_hz: float = 5e6
    n_tones: int = 64
    noise_figure_db: float = 7.0
    delay_error: str = "white"
    delay_corr_m: float = 20.0

    def __post_init__(self) -> None:
        if self.delay_error not in DELAY_ERRORS:
            raise ValueError(f"delay_error must be one of {DELAY_ERRORS}, got {self.delay_error!r}")
        if not self.delay_corr_m > 0:
            raise ValueError(f"delay_corr_m must be positive, got {self.delay_corr_m!r}")
        if self.n_slots < 3:
            raise ValueError(f"n_slots must be >= 3, got {self.n_slots!r}")
        for name in ("shadow_corr_m", "delay_sigma_s", "window_m", "bandwidth_hz"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)!r}")
        if self.shadow_sigma_db < 0:
            raise ValueError("shadow_sigma_db must be >= 0")


def shadow_field(
    rng: np.random.Generator, n_slots: int, length_m: float, sigma_db: float, corr_m: float, step_m: float = 1.0
) -> np.ndarray:
    """Per-slot shadowing along the tunnel [slot, x on a ``step_m`` grid] [dB], AR(1) with
    correlation exp(-dx / corr_m) (Gudmundson).

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of the field's draws.
    n_slots : int
        Number of slots (rows), each with its own field.
    length_m : float
        Length of the tunnel covered by the grid, from x = 0 [m].
    sigma_db : float
        Standard deviation of the field [dB] (the field takes its unit:
        :func:`delay_error_field` passes one in s).
    corr_m : float
        Correlation distance along the tunnel [m]; positive.
    step_m : float
        Grid step [m].

    Returns
    -------
    numpy.ndarray
        The stationary field [slot, ceil(length_m / step_m) + 1] at x = 0, step_m, ... [dB].
    """
    n = int(math.ceil(length_m / step_m)) + 1
    rho = math.exp(-step_m / corr_m)
    w = rng.standard_normal((n_slots, n))
    w[:, 1:] *= math.sqrt(1.0 - rho * rho)
    return sigma_db * lfilter([1.0], [1.0, -rho], w, axis=1)


def field_at(field: np.ndarray, slots: np.ndarray, x_m: np.ndarray, step_m: float = 1.0) -> np.ndarray:
    """A per-slot field along the tunnel (:func:`shadow_field`) read at receiver positions,
    linearly interpolated on its grid.

    Parameters
    ----------
    field : numpy.ndarray
        The field [slot, x on a ``step_m`` grid from 0].
    slots : numpy.ndarray
        Slot indices (int), any shape broadcastable with ``x_m``.
    x_m : numpy.ndarray
        Receiver positions [m] (clipped to the grid).
    step_m : float
        Grid step of ``field`` [m].

    Returns
    -------
    numpy.ndarray
        The field at (slot, x), the broadcast shape of ``slots`` and ``x_m``.
    """
    pos = np.clip(x_m / step_m, 0, field.shape[1] - 1.000001)
    i0 = pos.astype(np.int64)
    fr = pos - i0
    return field[slots, i0] * (1 - fr) + field[slots, i0 + 1] * fr


def delay_error_field(
    rng: np.random.Generator, n_slots: int, length_m: float, mm: MeasurementModel
) -> np.ndarray | None:
    """Per-slot delay error along the tunnel [slot, x on a 1 m grid] [s]; None if white.

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of the field's draws.
    n_slots : int
        Number of slots (rows).
    length_m : float
        Length of the tunnel covered by the grid, from x = 0 [m].
    mm : MeasurementModel
        ``delay_error`` (the time structure), ``delay_sigma_s`` [s], ``delay_corr_m`` [m].

    Returns
    -------
    numpy.ndarray or None
        [slot, ceil(length_m) + 1] [s]: ``ar1``, an AR(1) field of standard deviation
        ``delay_sigma_s`` correlated over ``delay_corr_m``; ``slot_bias``, one Gaussian bias
        per slot, constant along the tunnel; None for ``white``.
    """
    if mm.delay_error == "white":
        return None
    if mm.delay_error == "ar1":
        return shadow_field(rng, n_slots, length_m, mm.delay_sigma_s, mm.delay_corr_m)
    n = int(math.ceil(length_m)) + 1
    return np.repeat(mm.delay_sigma_s * rng.standard_normal((n_slots, 1)), n, axis=1)
