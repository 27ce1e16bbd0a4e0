"""Fast fading where a single look decides: the random-access occasions.

The handover's radio-link monitoring (T310, the command's reception, the new link) reads
local means: an out-of-sync indication judges the SINR over ``rlf_eval_s`` = 200 ms
(TS 36.133 §7.6), which spans at least 2 f_D·0.2 s ≈ 67 fades at 100 km/h and 1.8 GHz
(f_D = v f_c / c = 167 Hz), so fast fading leaves the window mean near the local mean; the
measurement report and the command ride on HARQ and RLC ARQ (TS 36.321 §5.4, TS 36.322),
several looks ≥ 8 ms apart. A random-access preamble is one look (TS 36.321 §5.1: no HARQ
for Msg1; a failed occasion is a new preamble at the next occasion), so the access stage
reads the SINR with fast fading on both links at each PRACH occasion.

The model (per handover and link): a Rician channel h(t) = √(K/(K+1)) e^{jφ(t)} +
√(1/(K+1)) g(t) with unit mean power, g a complex Gaussian process with Clarke's
autocorrelation J0(2π f_D τ) (isotropic scattering around the train), the LOS phase
φ(t) = φ0 + 2π f_D cos θ t (θ between the track and the RRH, φ0 uniform). K from TR 38.901
Table 7.5-6 (RMa LOS: μ_K = 7 dB); K = 0 is Rayleigh. The occasions' diffuse samples are
drawn jointly with their exact covariance (a Cholesky factor of the J0 matrix), so the
correlation between occasions 10 ms apart is exact at every speed, not assumed zero.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.special import j0

from railradio.constants import SPEED_OF_LIGHT_M_S

FADING_MODELS = ("none", "rayleigh", "rician")


def clarke_factor(n: int, f_d_hz: float, dt_s: float) -> NDArray[np.float64]:
    """Lower-triangular L with L Lᵀ = R + 10⁻⁹ I, R_ij = J0(2π f_D |i − j| dt) (Clarke's
    autocorrelation of the diffuse part at ``n`` samples ``dt_s`` apart).

    Raises
    ------
    ValueError
        If ``n`` < 1, ``f_d_hz`` < 0 or ``dt_s`` ≤ 0.
    """
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n!r}")
    if not f_d_hz >= 0.0:
        raise ValueError(f"f_d_hz must be >= 0, got {f_d_hz!r}")
    if not dt_s > 0.0:
        raise ValueError(f"dt_s must be > 0, got {dt_s!r}")
    lag = np.abs(np.arange(n)[:, None] - np.arange(n)[None, :])
    r = j0(2.0 * math.pi * f_d_hz * dt_s * lag)
    # R is positive semi-definite (a sampled autocorrelation) and singular for a slow train
    # (R -> all ones); 1e-9 on the diagonal makes the Cholesky factor exist (unique, so the
    # same on every machine, unlike an eigenvector basis) at a variance error of 1e-9
    return np.linalg.cholesky(r + 1e-9 * np.eye(n))


def power_gains_db(
    white: NDArray, phase0: NDArray, k_db: float | None, f_d_hz: float, dt_s: float, cos_los: NDArray, t0_s: float = 0.0
) -> NDArray[np.float64]:
    """Fast-fading power gain |h|² [dB] at ``n`` instants ``t0_s + i·dt_s``.

    Parameters
    ----------
    white : numpy.ndarray
        Standard normals [..., n, 2] (real and imaginary parts of the diffuse part's
        innovations).
    phase0 : numpy.ndarray
        Uniform draws in [0, 1) [...]: the LOS phase at t = 0 in turns.
    k_db : float or None
        Rician K-factor [dB]; ``None``: Rayleigh (no LOS part).
    f_d_hz : float
        Maximum Doppler frequency v f_c / c [Hz].
    dt_s : float
        Time between the instants [s].
    cos_los : numpy.ndarray
        cos θ of the LOS direction against the direction of travel [...] (its Doppler
        f_D cos θ).
    t0_s : float, optional
        Time of the first instant [s].

    Returns
    -------
    numpy.ndarray
        10 log10 |h|² [dB], [..., n]; E|h|² = 1.
    """
    w = np.asarray(white, dtype=float)
    if w.ndim < 2 or w.shape[-1] != 2:
        raise ValueError(f"white must be [..., n, 2], got shape {w.shape}")
    n = w.shape[-2]
    lf = clarke_factor(n, f_d_hz, dt_s)
    z = (w[..., 0] + 1j * w[..., 1]) / math.sqrt(2.0)  # unit-power complex normals
    g = z @ lf.T
    if k_db is None:
        h = g
    else:
        k = 10.0 ** (k_db / 10.0)
        t = t0_s + dt_s * np.arange(n)
        phi = 2.0 * math.pi * (np.asarray(phase0, dtype=float)[..., None] + f_d_hz * np.asarray(cos_los)[..., None] * t)
        h = math.sqrt(k / (k + 1.0)) * np.exp(1j * phi) + math.sqrt(1.0 / (k + 1.0)) * g
    return 10.0 * np.log10(np.maximum(np.abs(h) ** 2, 1e-30))


def doppler_hz(speed_m_s: float, carrier_hz: float) -> float:
    """Maximum Doppler frequency f_D = v f_c / c [Hz]."""
    return speed_m_s * carrier_hz / SPEED_OF_LIGHT_M_S
