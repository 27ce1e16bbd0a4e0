"""The handover band of the joint decision and the WSLR compensation (reconstruction
eq. 4–7, 10–15; our reconstruction of the source's lost equations).

Model gap (completion coordinates, h ≪ L): Ĝ(x) = â + 10 n̂ log10((x_t − x)/(x − x_s)).
"""

from __future__ import annotations

import math

import numpy as np

from railradio.handover.params import Joint, Radio


def gap_threshold_db(sigma0_db: float, joint: Joint) -> float:
    """GapH(v, σ0) [dB] (reconstruction eq. 5).

    ``widen`` (default): Γ + κσ0 — the band widens as noise grows, as the source says;
    ``narrow``: max(Γ − κσ0, floor).  Its speed dependence is the band shift v·T0 (eq. 6).
    """
    if sigma0_db < 0:
        raise ValueError(f"sigma0_db must be >= 0, got {sigma0_db!r}")
    if joint.gaph_rule == "widen":
        return joint.gaph_gamma_db + joint.gaph_kappa * sigma0_db
    return max(joint.gaph_gamma_db - joint.gaph_kappa * sigma0_db, joint.gaph_floor_db)


def log_ratio(x_m, radio: Radio) -> np.ndarray:
    """The regressor log10((x_t − x)/(x − x_s)) of the model gap (h neglected).

    Defined for x_s < x < x_t; positions outside are clipped 1 cm inside.
    """
    x = np.clip(np.asarray(x_m, dtype=float), radio.x_serving_m + 0.01, radio.x_target_m - 0.01)
    return np.log10((radio.x_target_m - x) / (x - radio.x_serving_m))


def model_gap_db(x_m, a_db, n_hat, radio: Radio) -> np.ndarray:
    """Ĝ(x) = â + 10 n̂ log10((x_t − x)/(x − x_s)) [dB] (reconstruction eq. 4/6)."""
    return np.asarray(a_db) + 10.0 * np.asarray(n_hat) * log_ratio(x_m, radio)


def inverse_gap_m(g_db, a_db, n_hat, radio: Radio) -> np.ndarray:
    """Ĝ⁻¹(g) = x_s + L/(1 + 10^((g − â)/(10 n̂))) [m] (reconstruction eq. 12)."""
    g = np.asarray(g_db, dtype=float)
    return radio.x_serving_m + radio.spacing_m / (1.0 + 10.0 ** ((g - a_db) / (10.0 * np.asarray(n_hat))))


def band_edges_m(gaph_db: float, a_db, n_hat, radio: Radio) -> tuple[np.ndarray, np.ndarray]:
    """Completion band [PL_e, PR_e] = {x : |Ĝ(x)| ≤ GapH} [m] (reconstruction eq. 6–7).

    Q = 10^(GapH/(10 n̂)) is the boundary factor, r = 10^(−â/(10 n̂)):
    PL_e = x_s + L/(1 + Q r), PR_e = x_s + L Q/(Q + r).
    """
    if gaph_db <= 0:
        raise ValueError(f"gaph_db must be > 0, got {gaph_db!r}")
    n_hat = np.asarray(n_hat, dtype=float)
    q = 10.0 ** (gaph_db / (10.0 * n_hat))
    r = 10.0 ** (-np.asarray(a_db, dtype=float) / (10.0 * n_hat))
    pl = radio.x_serving_m + radio.spacing_m / (1.0 + q * r)
    pr = radio.x_serving_m + radio.spacing_m * q / (q + r)
    return pl, pr


def fit_from_sums(s1, sr, srr, sg, srg, joint: Joint, n_known: float):
    """Least-squares (â, n̂) of g = â + 10 n̂ r from running sums (reconstruction eq. 6).

    s1 = count, sr = Σr, srr = Σr², sg = Σg, srg = Σrg.  ``band_fit = offset`` keeps
    n̂ = n_known; otherwise n̂ = slope/10 clipped to ``exponent_bounds`` and â re-fit with it.
    A degenerate design (fewer than 2 distinct regressors) falls back to n̂ = n_known.
    """
    s1 = np.asarray(s1, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        if joint.band_fit == "offset":
            n_hat = np.full(np.shape(s1), float(n_known))
        else:
            den = s1 * srr - sr * sr
            ok = den > 1e-12 * np.maximum(s1 * srr, 1e-300)
            slope = np.where(ok, (s1 * srg - sr * sg) / np.where(ok, den, 1.0), 10.0 * n_known)
            n_hat = np.clip(slope / 10.0, *joint.exponent_bounds)
        a_hat = np.where(s1 > 0, (sg - 10.0 * n_hat * sr) / np.where(s1 > 0, s1, 1.0), 0.0)
    return a_hat, n_hat


# --- WSLR (reconstruction eq. 10–11) ----------------------------------------------------


def geometric_weights(m: int, alpha: float) -> np.ndarray:
    """α_k = α(1 − α)^(k−1), k = 1…m (k = 1 the nearest predecessor), normalized to 1."""
    if not isinstance(m, (int, np.integer)) or m < 1:
        raise ValueError(f"m must be an integer >= 1, got {m!r}")
    if not 0.0 < alpha < 1.0:
        raise ValueError(f"alpha must be in (0, 1), got {alpha!r}")
    w = alpha * (1.0 - alpha) ** np.arange(m)
    return w / w.sum()


def wslr_predict(dev: np.ndarray, weights: np.ndarray, method: str) -> np.ndarray:
    """Predicted deviation of the next node from its predecessors' deviations.

    Parameters
    ----------
    dev
        [..., p] deviations of the p = 0…m available predecessors, column k−1 = the k-th
        nearest (node i−k); p may be smaller than m near the head.
    weights
        α_1…α_m, shape [..., m] broadcastable against ``dev`` (only the first p are used,
        renormalized).
    method
        ``regression``: minimize Σ α_k (D_{i−k} − β0 − β1 (i−k))², predict β0 + β1 i
        (with fewer than 2 predecessors the weighted mean); ``mean``: Σ α_k D_{i−k}.

    Returns
    -------
    ĉ of shape [...]; 0 with no predecessor (node 1).
    """
    if method not in ("regression", "mean"):
        raise ValueError(f"method must be 'regression' or 'mean', got {method!r}")
    dev = np.asarray(dev, dtype=float)
    p = dev.shape[-1]
    if p == 0:
        return np.zeros(dev.shape[:-1])
    w = np.asarray(weights, dtype=float)[..., :p]
    w = w / w.sum(axis=-1, keepdims=True)
    mean = (dev * w).sum(axis=-1)
    if method == "mean" or p < 2:
        return mean
    j = -np.arange(1, p + 1, dtype=float)  # predecessor positions relative to node i (i = 0)
    j_bar = (w * j).sum(axis=-1)
    dj = j - j_bar[..., None]
    sxx = (w * dj * dj).sum(axis=-1)
    slope = (w * dj * (dev - mean[..., None])).sum(axis=-1) / sxx
    return mean + slope * (0.0 - j_bar)


def position_correction_m(
    c_db, xm_m, pl_m, pr_retry_m, gaph_db: float, a_db, n_hat, dead_zone_db: float, radio: Radio
) -> np.ndarray:
    """Piecewise power→position compensation Δx (reconstruction eq. 12).

    Δx = 0 for |ĉ| ≤ ε; Ĝ⁻¹(Ĝ(Xm) − ĉ) − Xm for ε < |ĉ| ≤ GapH (the point where the model
    gap plus the predicted deviation equals the model gap at Xm); PR' − Xm for ĉ > GapH and
    PL − Xm for ĉ < −GapH, PR' = PR − v(T0 + TZ) the latest first execution that leaves a
    second attempt inside the band.  The corrected point is always kept in [PL, PR'].
    """
    c = np.asarray(c_db, dtype=float)
    xm = np.asarray(xm_m, dtype=float)
    g_xm = model_gap_db(xm, a_db, n_hat, radio)
    x_new = inverse_gap_m(g_xm - c, a_db, n_hat, radio)
    x_new = np.where(c > gaph_db, pr_retry_m, np.where(c < -gaph_db, pl_m, x_new))
    x_new = np.where(np.abs(c) <= dead_zone_db, xm, x_new)
    x_new = np.clip(x_new, pl_m, np.maximum(pr_retry_m, pl_m))
    return x_new - xm


def sigma0_and_gaph(radio: Radio, joint: Joint) -> tuple[float, float]:
    """(σ0, GapH) [dB] for the scenario's measurement noise and filter.

    Parameters
    ----------
    radio : Radio
        Measurement noise σ_m [dB], measurement period [s] and L3 filter coefficient k.
    joint : Joint
        ``measurements`` (``l3`` or ``raw``) and the GapH rule (Γ [dB], κ [1], widen or narrow, floor [dB]).

    Returns
    -------
    sigma0_db : float
        Standard deviation σ0 [dB] of a measured gap serving − target: √2·σ_m for raw samples,
        the L3-filtered gap's stationary std otherwise.
    gaph_db : float
        The gap threshold GapH [dB] of :func:`gap_threshold_db` at that σ0.
    """
    from railradio.handover.radio import filtered_gap_noise_std_db, l3_coefficient_at

    a = l3_coefficient_at(radio.l3_k, radio.meas_period_s, radio.l3_reference_period_s)
    if joint.measurements == "raw":
        sigma0 = math.sqrt(2.0) * radio.meas_sigma_db
    else:
        sigma0 = filtered_gap_noise_std_db(radio.meas_sigma_db, a)
    return sigma0, gap_threshold_db(sigma0, joint)
