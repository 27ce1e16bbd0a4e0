"""Closed-form reference values of the handover study, against which its simulated success rates are checked.

In the interference-limited regime (thermal noise neglected), with the other cell loaded by
η, an attempt at a point where both links have the same mean power succeeds iff the true
gap G = P_s − P_t satisfies

    Q_out + 10 log10 η ≤ G ≤ −(Q_in + 10 log10 η)        (serving at H_b, target at H_e)

(reconstruction eq. 8 with N → 0).  At the overlap centre X_c the mean gap is 0 and the
shadowing gives G ~ N(0, σ_G²), σ_G = σ √(2(1 − ρ_st)), so the first attempt there succeeds
with Φ(hi/σ_G) − Φ(lo/σ_G) (H_b and H_e taken at the same point: v·T0 ≪ d_cor).  For
η = 0.5, Q_out = −8 dB, Q_in = −6 dB, σ = 6 dB: Φ(9.01/8.49) − Φ(−11.01/8.49) = 0.758.
That is the earlier ``instant`` rule.  Under the default ``rlm`` rule the serving link fails
only by radio-link monitoring along the path (no closed form), and the target's access fails
if its SINR over the execution is below Q_out, i.e. G > −(Q_out + 10 log10 η): access at X_c
succeeds with Φ(−(Q_out + 10 log10 η)/σ_G) = Φ(11.01/8.49) = 0.903, an upper bound on a
first attempt there (radio-link failures before the command come on top).
"""

from __future__ import annotations

import math

from scipy.stats import norm

from railradio.handover.params import Radio


def gap_window_db(radio: Radio) -> tuple[float, float]:
    """(lo, hi) [dB]: the true gaps at which an attempt succeeds (noise neglected).

    Parameters
    ----------
    radio : Radio
        The radio parameters: the other cell's load η = ``load_factor`` [1], > 0, and the SINR
        thresholds Q_out = ``q_out_db`` and Q_in = ``q_in_db`` [dB].

    Returns
    -------
    lo : float
        Q_out + 10 log10 η [dB]: the lowest true gap serving − target at which the serving
        link's SINR is at least Q_out.
    hi : float
        −(Q_in + 10 log10 η) [dB]: the highest true gap at which the target's SINR is at least
        Q_in.

    Raises
    ------
    ValueError
        If ``load_factor`` is not > 0 (10 log10 η is undefined at η = 0).
    """
    if radio.load_factor <= 0:
        raise ValueError(f"load_factor must be > 0 for the interference-limited bound, got {radio.load_factor!r}")
    eta_db = 10.0 * math.log10(radio.load_factor)
    return radio.q_out_db + eta_db, -(radio.q_in_db + eta_db)


def gap_sigma_db(radio: Radio) -> float:
    """σ_G = σ √(2(1 − ρ_st)) [dB]: std of the shadowing part of the gap.

    Parameters
    ----------
    radio : Radio
        The radio parameters: the std σ = ``shadow_sigma_db`` [dB] of each link's shadowing and
        the correlation ρ_st = ``shadow_cross_corr`` [1] of the two links' shadowing.

    Returns
    -------
    float
        σ_G [dB], the standard deviation of the shadowing part of the gap serving − target.
    """
    return radio.shadow_sigma_db * math.sqrt(2.0 * (1.0 - radio.shadow_cross_corr))


def first_attempt_success_at_centre(radio: Radio) -> float:
    """Φ(hi/σ_G) − Φ(lo/σ_G): first-attempt success probability at X_c (noise neglected).

    Parameters
    ----------
    radio : Radio
        The radio parameters: load η = ``load_factor`` [1], > 0, thresholds Q_out and Q_in
        [dB], shadowing std σ [dB] and the links' shadowing correlation ρ_st [1].

    Returns
    -------
    float
        Probability [1] that the true gap G ~ N(0, σ_G²) lies in the window (lo, hi) of
        :func:`gap_window_db` (the earlier ``instant`` rule; Φ the standard normal CDF); with
        σ_G = 0, 1 if the window contains 0, else 0.

    Raises
    ------
    ValueError
        If ``load_factor`` is not > 0.
    """
    lo, hi = gap_window_db(radio)
    s = gap_sigma_db(radio)
    if s == 0.0:
        return float(lo <= 0.0 <= hi)
    return float(norm.cdf(hi / s) - norm.cdf(lo / s))


def t304_gap_hi_db(radio: Radio) -> float:
    """−(Q_out + 10 log10 η) [dB]: the highest true gap at which the target's access succeeds
    under the ``rlm`` rule (its SINR over the execution ≥ Q_out, noise neglected).

    Parameters
    ----------
    radio : Radio
        The radio parameters: load η = ``load_factor`` [1], > 0, and Q_out = ``q_out_db`` [dB].

    Returns
    -------
    float
        −(Q_out + 10 log10 η) [dB], the highest true gap serving − target (minus ``lo`` of
        :func:`gap_window_db`).

    Raises
    ------
    ValueError
        If ``load_factor`` is not > 0.
    """
    lo, _ = gap_window_db(radio)
    return -lo


def t304_success_at_centre(radio: Radio) -> float:
    """Φ(−(Q_out + 10 log10 η)/σ_G): access success at X_c under the ``rlm`` rule, an upper
    bound on a first attempt there (noise neglected; radio-link failure not counted).

    Parameters
    ----------
    radio : Radio
        The radio parameters: load η = ``load_factor`` [1], > 0, Q_out = ``q_out_db`` [dB],
        shadowing std σ [dB] and the links' shadowing correlation ρ_st [1].

    Returns
    -------
    float
        Probability [1] Φ(hi/σ_G), hi of :func:`t304_gap_hi_db` and Φ the standard normal CDF;
        with σ_G = 0, 1 if hi ≥ 0, else 0.

    Raises
    ------
    ValueError
        If ``load_factor`` is not > 0.
    """
    s = gap_sigma_db(radio)
    hi = t304_gap_hi_db(radio)
    if s == 0.0:
        return float(0.0 <= hi)
    return float(norm.cdf(hi / s))
