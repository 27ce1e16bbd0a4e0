"""Binomial confidence intervals for Monte Carlo rates, with clustered trials (the handover,
chain and nr fidelity studies' rates).

In the handover study, the N nodes of one train cross the same shadowing field, so the N·R node handovers of R
runs are not independent.  A rate's interval uses the effective number of trials
n_eff = p(1 − p)/Var(p̂), Var(p̂) from the spread of the per-run rates (between-cluster
variance), bounded to [R, N·R]; with no event (or all events) n_eff = R.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import beta, norm


def wilson_interval(k, n, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Wilson score interval of a binomial proportion k/n (k, n may be non-integer: n_eff).

    p̃ = (p̂ + z²/2n)/(1 + z²/n), half-width z/(1 + z²/n)·√(p̂(1 − p̂)/n + z²/4n²).
    """
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level!r}")
    k = np.asarray(k, dtype=float)
    n = np.asarray(n, dtype=float)
    if np.any(n <= 0) or np.any(k < 0) or np.any(k > n):
        raise ValueError("need n > 0 and 0 <= k <= n")
    z = norm.ppf(0.5 + level / 2)
    p = k / n
    den = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / den
    half = z / den * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    # p lies inside the interval; keep it there against rounding at p = 0 or 1
    return np.clip(np.minimum(centre - half, p), 0, 1), np.clip(np.maximum(centre + half, p), 0, 1)


def clopper_pearson_interval(k, n, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Exact (Clopper–Pearson) interval from beta quantiles; k, n may be non-integer."""
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level!r}")
    k = np.asarray(k, dtype=float)
    n = np.asarray(n, dtype=float)
    if np.any(n <= 0) or np.any(k < 0) or np.any(k > n):
        raise ValueError("need n > 0 and 0 <= k <= n")
    a = (1 - level) / 2
    with np.errstate(invalid="ignore"):
        lo = np.where(k > 0, beta.ppf(a, np.maximum(k, 1e-300), n - k + 1), 0.0)
        hi = np.where(k < n, beta.ppf(1 - a, k + 1, np.maximum(n - k, 1e-300)), 1.0)
    return lo, hi


def clustered_rate(events: np.ndarray, level: float = 0.95, method: str = "wilson") -> dict[str, float]:
    """Rate, its standard error and interval from events [R runs, N nodes] (bool/0-1).

    Returns p, se (cluster-robust), n (= R·N), n_eff, lo, hi.  NaN entries are ignored.
    """
    if method not in ("wilson", "clopper_pearson"):
        raise ValueError(f"method must be 'wilson' or 'clopper_pearson', got {method!r}")
    e = np.asarray(events, dtype=float)
    if e.ndim != 2:
        raise ValueError(f"events must be [runs, nodes], got shape {e.shape}")
    valid = ~np.isnan(e)
    n_run = valid.sum(axis=1)
    keep = n_run > 0
    e, valid, n_run = e[keep], valid[keep], n_run[keep]
    r = e.shape[0]
    n = float(n_run.sum())
    if r == 0:
        return {"p": math.nan, "se": math.nan, "n": 0.0, "n_eff": 0.0, "lo": math.nan, "hi": math.nan}
    k_run = np.where(valid, e, 0.0).sum(axis=1)
    p = float(k_run.sum() / n)
    # ratio-estimator variance of a clustered proportion
    if r > 1:
        resid = k_run - p * n_run
        var = float(r / (r - 1) * np.sum(resid * resid) / n / n)
    else:
        var = p * (1 - p) / n
    if 0 < p < 1 and var > 0:
        n_eff = min(max(p * (1 - p) / var, r), n)
    else:
        n_eff = float(r)
    se = math.sqrt(p * (1 - p) / n_eff)
    fn = wilson_interval if method == "wilson" else clopper_pearson_interval
    lo, hi = fn(p * n_eff, n_eff, level)
    return {"p": p, "se": se, "n": n, "n_eff": float(n_eff), "lo": float(lo), "hi": float(hi)}


def clustered_mean(values: np.ndarray) -> dict[str, float]:
    """Mean of values [R, N] (NaN ignored) and its cluster-robust standard error."""
    v = np.asarray(values, dtype=float)
    valid = ~np.isnan(v)
    n_run = valid.sum(axis=1)
    keep = n_run > 0
    v, valid, n_run = v[keep], valid[keep], n_run[keep]
    n = float(n_run.sum())
    if n == 0:
        return {"mean": math.nan, "se": math.nan, "n": 0.0}
    s_run = np.where(valid, v, 0.0).sum(axis=1)
    mean = float(s_run.sum() / n)
    r = v.shape[0]
    if r > 1:
        resid = s_run - mean * n_run
        se = math.sqrt(r / (r - 1) * np.sum(resid * resid)) / n
    else:
        se = math.nan
    return {"mean": mean, "se": float(se), "n": n}
