"""Physical limits of the nr study, and the predictions built on measured errors.

Bounds (functions of the signal model alone):

* TOA Cramér–Rao bound with interference: σ_τ ≥ 1 / (2π β_rms sqrt(2 Σ_b E_b/N0_b)), β_rms
  the RMS bandwidth of the 127-subcarrier PSS+SSS about its centroid, Δf sqrt((127² - 1)/12)
  ≈ 8.8 MHz; the sum runs over the blocks a detector finds (:func:`detected_blocks`): E_b
  the PSS+SSS energy of block b after its beam gain, N0_b the thermal noise of both chains
  plus, as Gaussian interference, what the other RRHs send on the PSS+SSS subcarriers
  during that block's symbols — their own SS block b on their beam b (every RRH sends its
  burst at the same instants; the data fill other symbols, :class:`railradio.nr.synthesis.synthesizer.Synthesizer`).
* The posterior CRB recursion of Tichavský et al. (1998) as a function of the
  per-measurement variances it is given (:func:`pcrb_m`).

Predictions (they use measured error levels, so they are not bounds):

* the integer-sample TOA floor c/(F_s √12) = 0.35 m of the source's estimator;
* the snapshot position error (PEB form) of an epoch's three best RRHs with the calibration
  run's AOD spread, J = Σ_j u_j u_jᵀ/σ_r,j² + u⊥_j u⊥_jᵀ/(ρ_j² σ_θ²);
* the PCRB recursion fed with those error levels — for the white-jerk model the tracker
  assumes (q calibrated), and for the true motion (constant acceleration within phases, an
  unknown jump at each known change: a genie-aided filter) [ours].
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.tracking.dynamics import process_noise, transition
from railradio.nr.tracking.measurement import jacobian
from railradio.nr.waveform.numerology import SAMPLE_RATE_HZ, SUBCARRIER_SPACING_HZ

PSS_SSS_SUBCARRIERS = 127
BETA_RMS_HZ = SUBCARRIER_SPACING_HZ * np.sqrt((PSS_SSS_SUBCARRIERS**2 - 1) / 12)
INTEGER_SAMPLE_SIGMA_M = SPEED_OF_LIGHT_M_S / SAMPLE_RATE_HZ / np.sqrt(12)


def toa_crb_s(e_over_n0: NDArray) -> NDArray[np.float64]:
    """σ_τ bound [s] for an energy-to-noise-density ratio E/N0 (linear; inf where 0).

    Parameters
    ----------
    e_over_n0 : array_like
        E/N0 (linear, 1; ≥ 0), e.g. :func:`burst_e_over_n0`.

    Returns
    -------
    numpy.ndarray
        Lower bound on the TOA standard deviation, s (same shape; inf where E/N0 = 0).
    """
    with np.errstate(divide="ignore"):
        return 1.0 / (2 * np.pi * BETA_RMS_HZ * np.sqrt(2.0 * np.asarray(e_over_n0, dtype=float)))


DETECT_K_SIGMA = 4.0
"""The source's detection threshold μ + 4σ (source eq. 6) on a Rayleigh floor of parameter σ_R:
μ = σ_R √(π/2), σ = σ_R √(2 - π/2)."""
DETECT_E_OVER_N0 = (np.sqrt(np.pi / 2) + DETECT_K_SIGMA * np.sqrt(2 - np.pi / 2)) ** 2 / 2
"""E_b/N0 at which a block's matched-filter peak √(2E_b/N0) σ_R reaches that threshold (7.50,
8.75 dB): the blocks a detector finds, in expectation."""


def block_e_over_n0(links, n_chains: int | None = None) -> NDArray[np.float64]:
    """[links, blocks] E_b/N0_b of every link's PSS+SSS in every SS block: its energy after
    the block's beam gain over thermal noise plus the other links' PSS+SSS of the same block
    (their beam b) as white interference over those subcarriers. ``links``: a
    :class:`railradio.nr.channel.link.Links`.

    Parameters
    ----------
    links : railradio.nr.channel.link.Links
        The epoch's links: ``amp`` [√W] [links], ``beam_amp`` [links, blocks], ``noise_psd_w_hz``
        [W/Hz], ``n_chains``.
    n_chains : int or None
        Receive chains whose thermal noise adds up (``None``: ``links.n_chains``).

    Returns
    -------
    numpy.ndarray
        E_b/N0_b (linear, 1), [links, blocks].
    """
    t_u = 1.0 / SUBCARRIER_SPACING_HZ
    chains = links.n_chains if n_chains is None else n_chains
    p_sc = links.amp[:, None] ** 2 * links.beam_amp**2  # [links, blocks] power per subcarrier [W]
    energy = 2 * PSS_SSS_SUBCARRIERS * p_sc * t_u  # PSS + SSS symbols [J]
    interf_psd = p_sc * t_u  # [W/Hz] on those subcarriers during block b
    n0 = links.noise_psd_w_hz * chains + (interf_psd.sum(axis=0)[None, :] - interf_psd)
    return energy / n0


def detected_blocks(e_over_n0_b: NDArray) -> NDArray[np.bool_]:
    """The blocks whose E_b/N0 reaches :data:`DETECT_E_OVER_N0`.

    Parameters
    ----------
    e_over_n0_b : array_like
        E_b/N0_b (linear, 1), e.g. [links, blocks] (:func:`block_e_over_n0`).

    Returns
    -------
    numpy.ndarray of bool
        Detected in expectation, same shape.
    """
    return np.asarray(e_over_n0_b) >= DETECT_E_OVER_N0


def burst_e_over_n0(links, n_chains: int | None = None) -> NDArray[np.float64]:
    """[links] Σ_b E_b/N0_b over each link's detected blocks (0 when none is): the TOA
    information of the burst, :func:`toa_crb_s` of it the bound.

    Parameters
    ----------
    links : railradio.nr.channel.link.Links
        The epoch's links (amplitudes, beam gains, noise PSD [W/Hz], receive chains).
    n_chains : int or None
        Receive chains whose thermal noise adds up (``None``: ``links.n_chains``).

    Returns
    -------
    numpy.ndarray
        [links] Σ_b E_b/N0_b (linear, 1).
    """
    e = block_e_over_n0(links, n_chains)
    return np.where(detected_blocks(e), e, 0.0).sum(axis=1)


def peb_m(rrh_xy: NDArray, x_m: float, dh_m: float, sigma_r_m: NDArray, sigma_theta_rad: float) -> float:
    """Snapshot 2-D position error [m] of the Fisher information of RRHs at ``rrh_xy`` [n, 2]
    with range and angle error levels ``sigma_r_m``, ``sigma_theta_rad`` (a bound when those
    are bounds, a prediction when they are measured).

    Parameters
    ----------
    rrh_xy : numpy.ndarray
        [n, 2] RRH positions (along-track x, lateral y), m.
    x_m : float
        Train position along the track (y = 0), m.
    dh_m : float
        RRH height above the train antenna, m.
    sigma_r_m : numpy.ndarray
        [n] range error standard deviations, m (> 0).
    sigma_theta_rad : float
        AOD error standard deviation, rad (> 0).

    Returns
    -------
    float
        sqrt(trace J⁻¹), m.

    Raises
    ------
    numpy.linalg.LinAlgError
        When the Fisher information is singular.
    """
    d = np.array([x_m, 0.0])[None, :] - rrh_xy
    rho = np.hypot(d[:, 0], d[:, 1])
    r3 = np.sqrt(rho**2 + dh_m**2)
    j = np.zeros((2, 2))
    for k in range(rrh_xy.shape[0]):
        u = d[k] / r3[k]  # ∂r/∂(x, y) (3-D range, horizontal gradient)
        up = np.array([-d[k, 1], d[k, 0]]) / rho[k]
        j += np.outer(u, u) / sigma_r_m[k] ** 2 + np.outer(up, up) / (rho[k] ** 2 * sigma_theta_rad**2)
    return float(np.sqrt(np.trace(np.linalg.inv(j))))


def change_epochs(phases, dt_s: float) -> NDArray[np.int64]:
    """First epoch of every trajectory phase after the first (the acceleration changes
    just before it); ``phases`` as in :class:`railradio.nr.channel.geometry.Trajectory`.

    Parameters
    ----------
    phases : sequence of (float, float)
        ``[(duration s, acceleration m/s²), ...]``.
    dt_s : float
        Epoch interval, s.

    Returns
    -------
    numpy.ndarray of int64
        [len(phases) - 1] epoch indices.
    """
    ends = np.cumsum([d for d, _ in phases])[:-1]
    return np.ceil(ends / dt_s - 1e-9).astype(np.int64)


def pcrb_m(
    rrh_xy_seq: list[NDArray],
    x_true: NDArray,
    dh_m: float,
    sigma_toa_s_seq: list[NDArray],
    sigma_theta_rad: float,
    dt_s: float,
    q: float,
    p0: NDArray,
    reset_epochs: NDArray | None = None,
    reset_acc_sigma: float = 10.0,
) -> NDArray[np.float64]:
    """Posterior CRB recursion of the 2-D position [m] along the track (Tichavský et al.
    1998) for the given measurement error levels (a prediction when they are measured).

    ``q`` [m² s⁻⁵] is the white-jerk intensity of the motion model (0: constant
    acceleration). ``reset_epochs``: epochs at which the acceleration jumps by an unknown
    amount (prior σ ``reset_acc_sigma`` [m/s²] per axis), added to the step's process noise.
    With q = 0 and the true trajectory's phase changes this is the bound of a genie that
    knows when the acceleration changes — a lower bound for any tracker of this
    piecewise-constant-acceleration trajectory [ours].

    Parameters
    ----------
    rrh_xy_seq : list of numpy.ndarray
        Per epoch, the [n_k, 2] positions (x, y) of the RRHs measured, m (n_k may be 0: no update).
    x_true : numpy.ndarray
        [epoch] true along-track positions, m.
    dh_m : float
        RRH height above the train antenna, m.
    sigma_toa_s_seq : list of numpy.ndarray
        Per epoch, the [n_k] TOA error standard deviations, s.
    sigma_theta_rad : float
        AOD error standard deviation, rad.
    dt_s : float
        Epoch interval, s.
    q : float
        White-jerk intensity, m² s⁻⁵ (≥ 0).
    p0 : numpy.ndarray
        [6, 6] prior covariance of the state [x, y, v_x, v_y, a_x, a_y] (SI units squared).
    reset_epochs : numpy.ndarray or None
        Epochs with an unknown acceleration jump.
    reset_acc_sigma : float
        Prior σ of that jump per axis, m/s².

    Returns
    -------
    numpy.ndarray
        [epoch] sqrt(P_xx + P_yy) of the bound, m.

    Raises
    ------
    ValueError
        When ``q`` < 0.
    """
    if q < 0:
        raise ValueError(f"q must be >= 0, got {q!r}")
    f = transition(dt_s)
    qm = process_noise(dt_s, q)
    q_reset = np.diag([0.0, 0.0, 0.0, 0.0, reset_acc_sigma**2, reset_acc_sigma**2])
    resets = set() if reset_epochs is None else {int(e) for e in reset_epochs}
    j = np.linalg.inv(p0)
    out = np.empty(len(rrh_xy_seq))
    for k, (xy, s_toa) in enumerate(zip(rrh_xy_seq, sigma_toa_s_seq, strict=True)):
        if k > 0:
            j = np.linalg.inv(qm + (q_reset if k in resets else 0.0) + f @ np.linalg.inv(j) @ f.T)
        if xy.shape[0]:
            s = np.array([x_true[k], 0.0, 0, 0, 0, 0])
            h = jacobian(s, xy, dh_m, "aod_toa")
            w = np.diag(np.ravel(np.column_stack([np.full(xy.shape[0], sigma_theta_rad**2), np.asarray(s_toa) ** 2])))
            j = j + h.T @ np.linalg.solve(w, h)
        cov = np.linalg.inv(j)
        out[k] = np.sqrt(cov[0, 0] + cov[1, 1])
    return out
