"""Radio model of the handover study: path loss, correlated shadowing, measurements,
the L3 filter and the SINR (reconstruction eq. 1–2; TS 36.331 §5.5.3.2).

Conventions: the serving RRH at x_s = 0 and the target at x_t = L_BS, both h off the
track; link index 0 = serving, 1 = target.  Every function is vectorized over arrays.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.signal import lfilter

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.handover.params import Radio

THERMAL_NOISE_DBM_HZ = -174.0


def free_space_loss_db(d_m: float, carrier_hz: float) -> float:
    """Free-space loss 20 log10(4π d / λ) [dB]."""
    if d_m <= 0 or carrier_hz <= 0:
        raise ValueError(f"d_m and carrier_hz must be > 0, got {d_m!r}, {carrier_hz!r}")
    return 20.0 * math.log10(4.0 * math.pi * d_m * carrier_hz / SPEED_OF_LIGHT_M_S)


def path_loss_db(d_m, radio: Radio) -> np.ndarray:
    """Mean log-distance path loss L(d0) + 10 n log10(d/d0) [dB] (source eq. 3, ζ excluded).

    L(d0) is the free-space loss at d0 [ours]; distances below d0 keep the same law.
    """
    d = np.asarray(d_m, dtype=float)
    if np.any(d <= 0):
        raise ValueError("d_m must be > 0")
    l0 = free_space_loss_db(radio.ref_distance_m, radio.carrier_hz)
    return l0 + 10.0 * radio.pathloss_exponent * np.log10(d / radio.ref_distance_m)


def link_distances_m(x_m, radio: Radio) -> tuple[np.ndarray, np.ndarray]:
    """3-D-free distances d_s, d_t [m] of track positions x to the serving and target RRH."""
    x = np.asarray(x_m, dtype=float)
    return (np.hypot(x - radio.x_serving_m, radio.offset_m), np.hypot(x - radio.x_target_m, radio.offset_m))


def pattern_loss_db(along_m, radio: Radio) -> np.ndarray:
    """Loss of an RRH's antenna pointed along the track at a train ``along_m`` from it along
    the track [dB] (≥ 0): TR 38.901 Table 7.3-1's horizontal pattern min(12 (φ/φ3dB)², A_max)
    with φ = atan(h/|along|) off boresight (back-to-back antennas, one each way along the
    line); 0 with ``antenna_hpbw_deg`` None (omnidirectional)."""
    if radio.antenna_hpbw_deg is None:
        return np.zeros(np.shape(along_m))
    phi_deg = np.degrees(np.arctan2(radio.offset_m, np.abs(np.asarray(along_m, dtype=float))))
    return np.minimum(12.0 * (phi_deg / radio.antenna_hpbw_deg) ** 2, radio.antenna_max_loss_db)


def mean_rsrp_dbm(x_m, radio: Radio) -> tuple[np.ndarray, np.ndarray]:
    """Mean received power P_tx − L(d) − A(φ) of the serving and target link at x [dBm]
    (P_tx the EIRP along the track, A the antenna's pattern loss, :func:`pattern_loss_db`)."""
    x = np.asarray(x_m, dtype=float)
    d_s, d_t = link_distances_m(x, radio)
    a_s = pattern_loss_db(x - radio.x_serving_m, radio)
    a_t = pattern_loss_db(x - radio.x_target_m, radio)
    return radio.tx_power_dbm - path_loss_db(d_s, radio) - a_s, radio.tx_power_dbm - path_loss_db(d_t, radio) - a_t


def sfn_rrh_positions_m(radio: Radio) -> tuple[np.ndarray, np.ndarray]:
    """Along-track positions [m] of every RRH of the serving and the target cell, nearest
    first: x_s − k·L_BS and x_t + k·L_BS for k < ``sfn_rrhs`` (TS 36.101 Annex B.3A's
    HST-SFN: RRHs every D_s along the line with one cell ID). With one RRH per cell, just
    x_s and x_t."""
    k = np.arange(radio.sfn_rrhs)
    return radio.x_serving_m - k * radio.spacing_m, radio.x_target_m + k * radio.spacing_m


def rrh_rsrp_dbm(x_m, radio: Radio) -> np.ndarray:
    """Mean received power P_tx − L(d) − A(φ) of every RRH of both cells at x [dBm]:
    shape [..., 2, K] (link 0 serving, 1 target; RRH 0 the nearest, :func:`sfn_rrh_positions_m`)."""
    x = np.asarray(x_m, dtype=float)[..., None, None]
    pos = np.stack(sfn_rrh_positions_m(radio))  # [2, K]
    d = np.hypot(x - pos, radio.offset_m)
    return radio.tx_power_dbm - path_loss_db(d, radio) - pattern_loss_db(x - pos, radio)


def sfn_shadowing(zeta_db: np.ndarray, zeta_other_db: np.ndarray, grid: ShadowGrid, radio: Radio) -> np.ndarray:
    """The shadowing [dB] on the grid that puts each cell's local mean at the power sum of its
    RRHs: ζ_eff = P_0 − 10 log10 Σ_k 10^((P_k − ζ_k)/10), with P_k the mean power of RRH k at
    the grid point. Its nearest RRH's mean minus ζ_eff is then the cell's local mean, so every
    reader of ``mean_rsrp_dbm − ζ`` sees the single-frequency cell (a position takes its
    nearest grid point's sum: the other RRHs' means, ≥ 10·n·log10(3) dB below the nearest's
    at the overlap centre, move by < 0.01 dB within half a grid step).

    Parameters
    ----------
    zeta_db : numpy.ndarray
        Shadowing of the nearest RRH of each cell [dB], [..., 2, G].
    zeta_other_db : numpy.ndarray
        Shadowing of the cells' other RRHs [dB], [..., 2, K − 1, G] (RRH k + 1 at index k).
    grid : ShadowGrid
        The grid of both.
    radio : Radio
        The radio links (``sfn_rrhs`` = K).

    Returns
    -------
    numpy.ndarray
        ζ_eff [dB], [..., 2, G]; ``zeta_db`` itself when K = 1.
    """
    k_n = radio.sfn_rrhs
    if zeta_other_db.shape[-2:] != (k_n - 1, grid.n) or zeta_other_db.shape[:-2] != zeta_db.shape[:-1]:
        raise ValueError(
            f"zeta_other_db must be [..., 2, {k_n - 1}, {grid.n}] beside zeta_db {zeta_db.shape}, "
            f"got {zeta_other_db.shape}"
        )
    if k_n == 1:
        return zeta_db
    p = np.moveaxis(rrh_rsrp_dbm(grid.x_m, radio), 0, -1)  # [2, K, G]
    rel = (p[:, 1:] - p[:, :1]) - zeta_other_db + zeta_db[..., None, :]  # RRH k against the nearest [dB]
    return zeta_db - 10.0 * np.log10(1.0 + np.sum(10.0 ** (rel / 10.0), axis=-2))


def noise_power_dbm(radio: Radio) -> float:
    """Thermal noise −174 dBm/Hz + 10 log10(B) + NF [dBm]."""
    return THERMAL_NOISE_DBM_HZ + 10.0 * math.log10(radio.bandwidth_hz) + radio.noise_figure_db


def sinr_db(p_wanted_dbm, p_other_dbm, radio: Radio) -> np.ndarray:
    """SINR = P_wanted − 10 log10(η·10^(P_other/10) + N) [dB] (reconstruction eq. 8)."""
    n_mw = 10.0 ** (noise_power_dbm(radio) / 10.0)
    other = radio.load_factor * 10.0 ** (np.asarray(p_other_dbm, dtype=float) / 10.0)
    return np.asarray(p_wanted_dbm, dtype=float) - 10.0 * np.log10(other + n_mw)


# --- correlated shadowing ---------------------------------------------------------------


def ar1_coefficient(step: float, corr_length: float) -> float:
    """ρ = exp(−|step|/corr_length) of an AR(1) (Gauss–Markov) process."""
    if corr_length <= 0:
        raise ValueError(f"corr_length must be > 0, got {corr_length!r}")
    return math.exp(-abs(step) / corr_length)


def ar1_process(white: np.ndarray, rho: float, sigma: float) -> np.ndarray:
    """Stationary AR(1) along the last axis from standard-normal ``white``.

    y[0] = σ w[0]; y[n] = ρ y[n−1] + σ√(1−ρ²) w[n]: the exact Gauss–Markov process with
    autocorrelation ρ^|Δn| on a regular grid (an IIR filter, vectorized over leading axes).
    """
    if not 0.0 <= rho < 1.0:
        raise ValueError(f"rho must be in [0, 1), got {rho!r}")
    u = np.array(white, dtype=float) * (sigma * math.sqrt(1.0 - rho * rho))
    u[..., 0] = sigma * white[..., 0]
    return lfilter([1.0], [1.0, -rho], u, axis=-1)


class ShadowGrid:
    """The grid along the track on which each run's shadowing field is drawn.

    Parameters
    ----------
    x_min_m, x_max_m
        Span of positions that can be queried [m] (positions outside are clipped).
    step_m
        Grid spacing [m]; a position takes its nearest grid value.
    """

    def __init__(self, x_min_m: float, x_max_m: float, step_m: float) -> None:
        if not x_max_m > x_min_m or step_m <= 0:
            raise ValueError(f"need x_max_m > x_min_m and step_m > 0, got {x_min_m}, {x_max_m}, {step_m}")
        self.x_min_m = float(x_min_m)
        self.step_m = float(step_m)
        self.n = int(math.ceil((x_max_m - x_min_m) / step_m)) + 1

    @property
    def x_m(self) -> np.ndarray:
        return self.x_min_m + self.step_m * np.arange(self.n)

    def index(self, x_m) -> np.ndarray:
        """Nearest grid index of positions x (clipped to the grid)."""
        i = np.rint((np.asarray(x_m, dtype=float) - self.x_min_m) / self.step_m)
        return np.clip(i, 0, self.n - 1).astype(np.intp)


def shadowing_fields(white: np.ndarray, grid: ShadowGrid, radio: Radio) -> np.ndarray:
    """Shadowing ζ [dB] of both links on the grid from standard normals.

    Parameters
    ----------
    white
        Standard normals of shape [..., 2, grid.n] (link 0 serving, 1 target).

    Returns
    -------
    ζ of the same shape: AR(1) in distance, ρ = exp(−Δ/d_cor) per grid step, σ_dB, and
    the target link mixed with the serving one to correlation ``shadow_cross_corr``.
    """
    if white.shape[-2:] != (2, grid.n):
        raise ValueError(f"white must end in (2, {grid.n}), got {white.shape}")
    rho = ar1_coefficient(grid.step_m, radio.shadow_corr_m)
    z = ar1_process(white, rho, radio.shadow_sigma_db)
    c = radio.shadow_cross_corr
    if c != 0.0:
        z[..., 1, :] = c * z[..., 0, :] + math.sqrt(1.0 - c * c) * z[..., 1, :]
    return z


# --- L3 filtering (TS 36.331 §5.5.3.2) ------------------------------------------------


def l3_coefficient(k: int) -> float:
    """a = 1/2^(k/4) of TS 36.331 §5.5.3.2 (k = 0: no filtering, a = 1)."""
    if not isinstance(k, (int, np.integer)) or k < 0:
        raise ValueError(f"k must be a non-negative integer, got {k!r}")
    return 1.0 / 2.0 ** (k / 4.0)


def l3_coefficient_at(k: int, period_s: float, reference_period_s: float = 0.2) -> float:
    """The coefficient with the same time characteristic at another sample period.

    TS 36.331 §5.5.3.2: k assumes a 200 ms sample rate and the UE adapts the filter to
    preserve its time characteristics: (1 − a') = (1 − a)^(T/200 ms), e.g. 0.129 for k = 4
    at 40 ms.
    """
    if period_s <= 0 or reference_period_s <= 0:
        raise ValueError("period_s and reference_period_s must be > 0")
    a = l3_coefficient(k)
    return 1.0 - (1.0 - a) ** (period_s / reference_period_s)


def l3_filter(m: np.ndarray, a: float) -> np.ndarray:
    """F_n = (1 − a) F_{n−1} + a M_n along the last axis, F at the first sample = M_1.

    TS 36.331 §5.5.3.2 (F_0 is set to M_1 when the first measurement arrives).
    """
    if not 0.0 < a <= 1.0:
        raise ValueError(f"a must be in (0, 1], got {a!r}")
    m = np.asarray(m, dtype=float)
    if a == 1.0:
        return m.copy()
    zi = (1.0 - a) * m[..., :1]
    return lfilter([a], [1.0, -(1.0 - a)], m, axis=-1, zi=zi)[0]


def filtered_gap_noise_std_db(meas_sigma_db: float, a: float) -> float:
    """σ0: std of a gap of two L3-filtered measurements with white errors σ_m.

    Steady-state variance of the first-order filter a σ²/(2 − a), for the difference of
    two independent links ×2 (reconstruction eq. 5).
    """
    return math.sqrt(2.0) * meas_sigma_db * math.sqrt(a / (2.0 - a))
