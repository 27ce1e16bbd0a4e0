"""Channel of the nr study, layered like TR 38.901: path loss -> shadowing -> small-scale.

* UMi street canyon LOS path loss (TR 38.901 Table 7.4.1-1) with the breakpoint
  d'_BP = 4 (h_BS - 1)(h_UT - 1) f_c / c;
* shadowing: Gaussian, σ = 4 dB, exp(-Δd/10 m) correlated along the track, independent
  per RRH (a Gauss–Markov field on a 1 m grid, independent of how the track is sharded);
* TDL-D (TR 38.901 Table 7.7.2-4; A, B, C, E from Tables 7.7.2-1/2/3/5 for the
  sensitivity cases) normalized to unit power: a LOS tap (D, E; none in the NLOS profiles
  A–C) with the geometric Doppler f_D cos α and Rayleigh taps from a sum-of-sinusoids
  (Clarke/Jakes) process.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cache
from importlib.resources import files

import numpy as np
from numpy.typing import NDArray

from railradio.constants import SPEED_OF_LIGHT_M_S


def breakpoint_distance_m(h_bs_m: float, h_ut_m: float, fc_hz: float) -> float:
    """UMi breakpoint d'_BP = 4 h'_BS h'_UT f_c / c with h' = h - 1 m [m].

    Parameters
    ----------
    h_bs_m : float
        Base-station (RRH) antenna height [m].
    h_ut_m : float
        User-terminal (train) antenna height [m].
    fc_hz : float
        Carrier frequency [Hz].

    Returns
    -------
    float
        Breakpoint distance d'_BP [m].
    """
    return 4.0 * (h_bs_m - 1.0) * (h_ut_m - 1.0) * fc_hz / SPEED_OF_LIGHT_M_S


def pathloss_umi_los_db(
    d3d_m: NDArray, d2d_m: NDArray, fc_hz: float, h_bs_m: float, h_ut_m: float
) -> NDArray[np.float64]:
    """TR 38.901 UMi-street-canyon LOS path loss [dB] (valid 10 m ≤ d2D ≤ 5 km).

    PL1 = 32.4 + 21 log10(d3D) + 20 log10(f_c/GHz) for d2D ≤ d'_BP,
    PL2 = 32.4 + 40 log10(d3D) + 20 log10(f_c/GHz) - 9.5 log10(d'_BP² + (h_BS - h_UT)²).

    Parameters
    ----------
    d3d_m : float or numpy.ndarray
        3-D distances [m]; all > 0.
    d2d_m : float or numpy.ndarray
        2-D distances [m] (select PL1 or PL2), the shape of ``d3d_m`` or broadcast with it.
    fc_hz : float
        Carrier frequency [Hz].
    h_bs_m : float
        RRH antenna height [m].
    h_ut_m : float
        Train antenna height [m].

    Returns
    -------
    numpy.ndarray
        Path loss [dB], the broadcast shape of ``d3d_m`` and ``d2d_m``.

    Raises
    ------
    ValueError
        When any ``d3d_m`` <= 0.
    """
    d3d = np.asarray(d3d_m, dtype=float)
    d2d = np.asarray(d2d_m, dtype=float)
    if np.any(d3d <= 0):
        raise ValueError("d3d_m must be > 0")
    fc_ghz = fc_hz / 1e9
    dbp = breakpoint_distance_m(h_bs_m, h_ut_m, fc_hz)
    pl1 = 32.4 + 21.0 * np.log10(d3d) + 20.0 * np.log10(fc_ghz)
    pl2 = 32.4 + 40.0 * np.log10(d3d) + 20.0 * np.log10(fc_ghz) - 9.5 * np.log10(dbp**2 + (h_bs_m - h_ut_m) ** 2)
    return np.where(d2d <= dbp, pl1, pl2)


def shadowing_field_db(
    rng: np.random.Generator, n_points: int, sigma_db: float, corr_dist_m: float, step_m: float = 1.0
) -> NDArray[np.float64]:
    """A stationary Gauss–Markov field on a grid: s[i+1] = ρ s[i] + σ √(1-ρ²) w,
    ρ = exp(-step/d_corr), s[0] ~ N(0, σ²): autocorrelation σ² exp(-|Δ|/d_corr) [dB].

    Parameters
    ----------
    rng : numpy.random.Generator
        Generator of the white innovations w.
    n_points : int
        Grid points; >= 1.
    sigma_db : float
        Standard deviation σ [dB]; >= 0.
    corr_dist_m : float
        Decorrelation distance d_corr [m]; > 0.
    step_m : float
        Grid step [m].

    Returns
    -------
    numpy.ndarray
        The field [dB]: [n_points], point i at i·step_m.

    Raises
    ------
    ValueError
        When ``sigma_db`` < 0, ``corr_dist_m`` <= 0 or ``n_points`` < 1.
    """
    if sigma_db < 0 or corr_dist_m <= 0 or n_points < 1:
        raise ValueError("sigma_db must be >= 0, corr_dist_m > 0, n_points >= 1")
    rho = np.exp(-step_m / corr_dist_m)
    w = rng.standard_normal(n_points)
    w[1:] *= np.sqrt(1.0 - rho**2)
    from scipy.signal import lfilter

    return sigma_db * lfilter([1.0], [1.0, -rho], w)


@dataclass(frozen=True)
class TdlProfile:
    """A TDL power-delay profile, normalized to unit total power.

    Attributes
    ----------
    los_power, los_delay_s
        Power [linear] and delay [s] of the specular LOS component (0 if NLOS).
    powers, delays_s
        Rayleigh taps [linear], [s].
    """

    name: str
    los_power: float
    los_delay_s: float
    powers: NDArray[np.float64]
    delays_s: NDArray[np.float64]

    @property
    def rice_k_db(self) -> float:
        """K-factor of the first tap: LOS vs the Rayleigh tap at the same delay [dB];
        -inf for an NLOS profile (TDL-A, B, C: no specular component).

        Returns
        -------
        float
            Rice K-factor [dB].
        """
        if self.los_power == 0.0:
            return float("-inf")
        first = self.powers[self.delays_s == self.los_delay_s].sum()
        return float(10 * np.log10(self.los_power / first))


@cache
def _table() -> dict:
    return json.loads((files("railradio") / "data" / "tdl.json").read_text(encoding="utf-8"))


def tdl_profile(name: str, delay_spread_s: float) -> TdlProfile:
    """Load a TDL profile from package data, scale delays by the delay spread, normalize.

    Parameters
    ----------
    name : str
        Profile name in ``railradio/data/tdl.json``: ``"TDL-A"`` … ``"TDL-E"``.
    delay_spread_s : float
        RMS delay spread [s] that scales the table's normalized delays; > 0.

    Returns
    -------
    TdlProfile
        Powers normalized to unit total power [linear], delays [s].

    Raises
    ------
    ValueError
        When ``name`` is not in the table or ``delay_spread_s`` <= 0.
    """
    table = _table()
    if name not in table:
        raise ValueError(f"TDL profile must be one of {sorted(k for k in table if k[0] != '_')}, got {name!r}")
    if not delay_spread_s > 0:
        raise ValueError(f"delay_spread_s must be > 0, got {delay_spread_s!r}")
    t = table[name]
    los = t.get("los_tap")
    pw = np.array([10 ** (x["power_db"] / 10) for x in t["rayleigh_taps"]])
    dl = np.array([x["delay"] for x in t["rayleigh_taps"]]) * delay_spread_s
    p_los = 10 ** (los["power_db"] / 10) if los else 0.0
    total = p_los + pw.sum()
    return TdlProfile(name, p_los / total, (los["delay"] * delay_spread_s) if los else 0.0, pw / total, dl)


def sos_params(rng: np.random.Generator, n_taps: int, n_sinusoids: int) -> tuple[NDArray, NDArray]:
    """Random arrival angles α and phases φ [rad] of a sum-of-sinusoids process, [taps, M].

    Parameters
    ----------
    rng : numpy.random.Generator
        Generator of the draws (α first, then φ).
    n_taps : int
        Number of taps L.
    n_sinusoids : int
        Sinusoids per tap M.

    Returns
    -------
    tuple of numpy.ndarray
        (α [rad], φ [rad]), each uniform on [0, 2π): [n_taps, n_sinusoids].
    """
    alpha = rng.uniform(0, 2 * np.pi, size=(n_taps, n_sinusoids))
    phi = rng.uniform(0, 2 * np.pi, size=(n_taps, n_sinusoids))
    return alpha, phi


def sos_eval(
    powers: NDArray, doppler_hz: float, times_s: NDArray, alpha: NDArray, phi: NDArray
) -> NDArray[np.complex128]:
    """Evaluate a sum-of-sinusoids process with given (α, φ) at ``times_s``: [n_times, n_taps].

    Parameters
    ----------
    powers : numpy.ndarray
        Tap powers P_l [linear]: [n_taps].
    doppler_hz : float
        Maximum Doppler f_D [Hz].
    times_s : numpy.ndarray
        Evaluation times [s]: [n_times].
    alpha : numpy.ndarray
        Arrival angles α [rad]: [n_taps, M] (:func:`sos_params`).
    phi : numpy.ndarray
        Phases φ [rad]: [n_taps, M].

    Returns
    -------
    numpy.ndarray of complex
        Tap gains [√linear]: [n_times, n_taps] (phases evaluated in float32).
    """
    powers = np.asarray(powers, dtype=float)
    f = doppler_hz * np.cos(alpha)
    t = np.asarray(times_s, dtype=float)
    # phases reduced mod 2π in float64, then evaluated in float32 (error < 1e-6 rad)
    phase = np.mod(2 * np.pi * f[None, :, :] * t[:, None, None] + phi[None, :, :], 2 * np.pi).astype(np.float32)
    s = np.cos(phase).sum(axis=-1) + 1j * np.sin(phase).sum(axis=-1)
    return np.sqrt(powers / alpha.shape[1])[None, :] * s


def sos_taps(
    rng: np.random.Generator, powers: NDArray, doppler_hz: float, times_s: NDArray, n_sinusoids: int = 32
) -> NDArray[np.complex128]:
    """Rayleigh tap gains by a sum of sinusoids (Clarke's model, random arrival angles).

    a_l(t) = sqrt(P_l / M) Σ_m exp(j(2π f_D cos α_{l,m} t + φ_{l,m})), α, φ ~ U[0, 2π):
    E|a_l|² = P_l, autocorrelation → P_l J0(2π f_D τ) as M grows.

    Parameters
    ----------
    rng : numpy.random.Generator
        Generator of α and φ (:func:`sos_params`).
    powers : numpy.ndarray
        Tap powers P_l [linear]: [n_taps].
    doppler_hz : float
        Maximum Doppler f_D [Hz].
    times_s : numpy.ndarray
        Evaluation times [s]: [n_times].
    n_sinusoids : int
        Sinusoids per tap M.

    Returns
    -------
    numpy.ndarray of complex
        Tap gains a_l(t) [√linear]: [n_times, n_taps].
    """
    alpha, phi = sos_params(rng, np.asarray(powers).size, n_sinusoids)
    return sos_eval(powers, doppler_hz, times_s, alpha, phi)
