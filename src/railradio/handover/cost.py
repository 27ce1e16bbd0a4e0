"""Parameter selection of the joint decision: the cost of (m, α) (reconstruction eq. 13–15,
source Fig. 4).

J(m, A) = E[C/N] + E[F(A)], C the convergence price (index of the first node whose measured
gap at its trigger is below the convergence threshold; N + 1 if none), F the fluctuation
level std(X_1…X_N)/(PR − PL) clipped to 1.  Weights: the one-parameter geometric family
α_k ∝ α(1 − α)^(k−1) over m ∈ 1…6, α ∈ 0.01…0.99 [ours: the source's literal per-element
grid is 99^m points]; as a check a full per-element grid (step 0.05) for 2 ≤ m ≤ 3 (for
m = 1 every weight vector normalises to [1], so the check cannot fail there).

The search is reported with its Monte Carlo error: the argmin, and the set of settings
within one standard error of the minimum (J ≤ J_min + SE(J_min), the one-standard-error
rule of Hastie, Tibshirani and Friedman, *The Elements of Statistical Learning* §7.10),
which says which settings the runs cannot tell apart.  The full grid's minimum is a minimum
over thousands of noisy estimates, so its gain over the family is biased upward; its paired
standard error (the same runs) is reported beside it.

The cost runs use their own random stream (``stream="cost"``), never the evaluation runs.
"""

from __future__ import annotations

import itertools

import numpy as np
import xarray as xr

from railradio.handover.model import build_context, draw_block
from railradio.handover.params import Scenario
from railradio.handover.policies import head_band, joint_nodes
from railradio.handover.train import kinematics

METHODS = ("regression", "mean")


def geometric_weight_table(m: int, alphas: np.ndarray) -> np.ndarray:
    """[A, m] geometric weights α(1 − α)^(k−1), one row per α (normalized in the WSLR).

    Parameters
    ----------
    m : int
        Number of weights per row: the number of joint nodes m.
    alphas : numpy.ndarray
        Geometric weight parameters α [1], shape [A], each in (0, 1).

    Returns
    -------
    numpy.ndarray
        Weights [1], shape [A, m]: row a holds α_a(1 − α_a)^(k−1) for k = 1…m (k = 1 the
        nearest predecessor), not normalized.

    Raises
    ------
    ValueError
        If an α is outside (0, 1).
    """
    alphas = np.asarray(alphas, dtype=float)
    if np.any((alphas <= 0) | (alphas >= 1)):
        raise ValueError("alphas must be in (0, 1)")
    return alphas[:, None] * (1.0 - alphas[:, None]) ** np.arange(m)[None, :]


def full_weight_table(m: int, step: float) -> np.ndarray:
    """[A, m] every per-element weight vector with elements step, 2·step, … < 1.

    Parameters
    ----------
    m : int
        Number of weights per vector: the number of joint nodes m.
    step : float
        Grid step of each element [1], in (0, 1).

    Returns
    -------
    numpy.ndarray
        Weights [1], shape [A, m] with A = (round(1/step) − 1)^m: every vector whose elements
        each take the values j·step, j = 1 … round(1/step) − 1, in lexicographic order; not
        normalized (the WSLR normalizes them).

    Raises
    ------
    ValueError
        If ``step`` is outside (0, 1).
    """
    if not 0 < step < 1:
        raise ValueError(f"step must be in (0, 1), got {step!r}")
    vals = np.arange(1, int(round(1 / step))) * step
    return np.array(list(itertools.product(vals, repeat=m)))


def _block_costs(ctx, band, weights: np.ndarray, method: str, chunk: int = 1024) -> np.ndarray:
    """Per-run cost C/N + F for each weight vector: [A, B]."""
    out = []
    for s in range(0, weights.shape[0], chunk):
        res = joint_nodes(ctx, band, weights[s : s + chunk], method)
        out.append(res["conv_price"] / ctx.n_nodes + res["fluct"])
    return np.concatenate(out, axis=0)


def cost_grid(
    scn: Scenario,
    speed_kmh: float,
    seed: int,
    n_blocks: int,
    runs_per_block: int,
    m_values: list[int],
    alphas: np.ndarray,
    full_grid_max_m: int = 3,
    full_grid_step: float = 0.05,
) -> xr.Dataset:
    """The cost J over (method, m, α), its Monte Carlo standard error, and the full-grid check.

    Parameters
    ----------
    scn : Scenario
        The scenario (``joint.m`` and ``joint.alpha`` are not used; ``joint.wslr`` picks the
        method of the full-grid check).
    speed_kmh : float
        Train speed of the cost runs [km/h], 1 ≤ v ≤ 1000.
    seed : int
        Root seed; the runs use the separate ``cost`` random stream.
    n_blocks : int
        Blocks of crossings, ≥ 1.
    runs_per_block : int
        Train crossings per block, ≥ 1.
    m_values : list of int
        Numbers of joint nodes m to evaluate (each ≥ 1).
    alphas : numpy.ndarray
        Geometric weight parameters α [1], each in (0, 1).
    full_grid_max_m : int, optional
        The full per-element weight grid is checked for 2 ≤ m ≤ this (default 3).
    full_grid_step : float, optional
        Step of the full weight grid [1], in (0, 1) (default 0.05).

    Returns
    -------
    xarray.Dataset
        Over dims ``wslr`` (``regression``, ``mean``), ``m`` and ``alpha`` [all 1]: ``cost``
        J = E[C/N] + E[F] and ``cost_se`` (wslr, m, alpha); ``cost_min_m``, ``cost_min_m_se``
        (wslr, m); ``within_1se`` (wslr, m, alpha, bool); ``cost_min_full_grid``,
        ``full_grid_gain``, ``full_grid_gain_se`` (m; NaN where not computed); ``best_m``,
        ``best_alpha`` (wslr); scalars ``speed_kmh`` [km/h], ``n_runs`` and ``full_grid_step``;
        attribute ``config_wslr``.

    Raises
    ------
    ValueError
        If ``n_blocks`` or ``runs_per_block`` < 1, an α is outside (0, 1), ``full_grid_step``
        is outside (0, 1) (when the full grid is computed), or the speed is out of range.
    """
    if n_blocks < 1 or runs_per_block < 1:
        raise ValueError("n_blocks and runs_per_block must be >= 1")
    alphas = np.asarray(alphas, dtype=float)
    full_m = [m for m in m_values if 2 <= m <= full_grid_max_m]
    per_run, full_runs = _run_costs(
        scn, speed_kmh, seed, n_blocks, runs_per_block, m_values, alphas, full_m, full_grid_step
    )
    cost, cost_se = _cost_mean_se(per_run, len(m_values), alphas.size)
    full = _full_grid_check(per_run, full_runs, m_values, METHODS.index(scn.joint.wslr))
    ds = _cost_dataset(cost, cost_se, full, m_values, alphas)
    ds["speed_kmh"] = xr.Variable((), float(speed_kmh), {"units": "km/h", "long_name": "train speed"})
    ds["n_runs"] = xr.Variable((), n_blocks * runs_per_block, {"units": "1", "long_name": "crossings"})
    ds["full_grid_step"] = xr.Variable((), full_grid_step, {"units": "1", "long_name": "step of the full weight grid"})
    ds.attrs["config_wslr"] = scn.joint.wslr
    return ds


def _run_costs(
    scn: Scenario,
    speed_kmh: float,
    seed: int,
    n_blocks: int,
    runs_per_block: int,
    m_values: list[int],
    alphas: np.ndarray,
    full_m: list[int],
    full_grid_step: float,
) -> tuple[dict[str, list[list[np.ndarray]]], dict[int, list[np.ndarray]]]:
    """Per-run costs of every block (``stream="cost"``): per WSLR method and m, the [A, B]
    costs of the geometric family per block; per m of ``full_m``, the [A_full, B] costs of
    the full grid (config WSLR method) per block."""
    kin = kinematics(scn, speed_kmh)
    per_run = {meth: [[] for _ in m_values] for meth in METHODS}
    full_runs = {m: [] for m in full_m}
    for blk in range(n_blocks):
        draws = draw_block(seed, speed_kmh, blk, runs_per_block, kin, scn.train.n_nodes, stream="cost")
        ctx = build_context(scn, kin, draws)
        band = head_band(ctx)
        for meth in METHODS:
            for j, m in enumerate(m_values):
                per_run[meth][j].append(_block_costs(ctx, band, geometric_weight_table(m, alphas), meth))
        for m in full_m:
            full_runs[m].append(_block_costs(ctx, band, full_weight_table(m, full_grid_step), scn.joint.wslr))
    return per_run, full_runs


def _cost_mean_se(per_run: dict[str, list[list[np.ndarray]]], n_m: int, n_alpha: int) -> tuple[np.ndarray, np.ndarray]:
    """The cost J [wslr, m, alpha] (mean over runs) and its Monte Carlo standard error."""
    cost = np.zeros((len(METHODS), n_m, n_alpha))
    cost_se = np.zeros_like(cost)
    for a, meth in enumerate(METHODS):
        for j in range(n_m):
            c = np.concatenate(per_run[meth][j], axis=1)  # [A, R]
            cost[a, j] = c.mean(axis=1)
            cost_se[a, j] = c.std(axis=1, ddof=1) / np.sqrt(c.shape[1])
    return cost, cost_se


def _full_grid_check(
    per_run: dict[str, list[list[np.ndarray]]], full_runs: dict[int, list[np.ndarray]], m_values: list[int], i_cfg: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per m: the full grid's min J, the geometric family's min J minus it on the same runs
    (method ``METHODS[i_cfg]``) and that gain's paired standard error (NaN: not computed)."""
    n_m = len(m_values)
    full_min = np.full(n_m, np.nan)
    full_gain = np.full(n_m, np.nan)
    full_gain_se = np.full(n_m, np.nan)
    for j, m in enumerate(m_values):
        if m in full_runs:
            cf = np.concatenate(full_runs[m], axis=1)  # [A_full, R]
            jf = int(cf.mean(axis=1).argmin())
            full_min[j] = cf[jf].mean()
            cg = np.concatenate(per_run[METHODS[i_cfg]][j], axis=1)  # [A, R]
            d = cg[int(cg.mean(axis=1).argmin())] - cf[jf]  # paired, per run
            full_gain[j] = d.mean()
            full_gain_se[j] = d.std(ddof=1) / np.sqrt(d.size)
    return full_min, full_gain, full_gain_se


def _cost_dataset(
    cost: np.ndarray,
    cost_se: np.ndarray,
    full: tuple[np.ndarray, np.ndarray, np.ndarray],
    m_values: list[int],
    alphas: np.ndarray,
) -> xr.Dataset:
    """The cost dataset: J and its standard error, the minima over alpha, the settings
    within one standard error of the minimum, the argmin (m, alpha) per WSLR method and the
    full-grid check ``full`` of :func:`_full_grid_check`."""
    full_min, full_gain, full_gain_se = full
    best = cost.reshape(len(METHODS), -1).argmin(axis=1)
    best_m = np.array([m_values[i // alphas.size] for i in best])
    best_alpha = np.array([alphas[i % alphas.size] for i in best])
    flat_se = cost_se.reshape(len(METHODS), -1)
    threshold = cost.reshape(len(METHODS), -1).min(axis=1) + flat_se[np.arange(len(METHODS)), best]
    within = cost <= threshold[:, None, None]
    ia = cost.argmin(axis=2)  # [wslr, m]
    cost_min_m = np.take_along_axis(cost, ia[..., None], axis=2)[..., 0]
    cost_min_m_se = np.take_along_axis(cost_se, ia[..., None], axis=2)[..., 0]
    return xr.Dataset(
        {
            "cost": (
                ("wslr", "m", "alpha"),
                cost,
                {"units": "1", "long_name": "cost J = E[C/N] + E[F] (geometric weights)"},
            ),
            "cost_se": (
                ("wslr", "m", "alpha"),
                cost_se,
                {"units": "1", "long_name": "Monte Carlo standard error of J"},
            ),
            "cost_min_m": (("wslr", "m"), cost_min_m, {"units": "1", "long_name": "min over alpha of J"}),
            "cost_min_m_se": (
                ("wslr", "m"),
                cost_min_m_se,
                {"units": "1", "long_name": "Monte Carlo standard error of min over alpha of J"},
            ),
            "within_1se": (
                ("wslr", "m", "alpha"),
                within,
                {"units": "1", "long_name": "J within one standard error of the minimum (J <= J_min + SE(J_min))"},
            ),
            "cost_min_full_grid": (
                ("m",),
                full_min,
                {
                    "units": "1",
                    "long_name": "min J over the full per-element weight grid (config WSLR method; NaN: not computed)",
                },
            ),
            "full_grid_gain": (
                ("m",),
                full_gain,
                {
                    "units": "1",
                    "long_name": "min J of the geometric family minus min J of the "
                    "full grid, same runs (config WSLR; NaN: not computed)",
                },
            ),
            "full_grid_gain_se": (
                ("m",),
                full_gain_se,
                {"units": "1", "long_name": "paired standard error of full_grid_gain"},
            ),
            "best_m": (("wslr",), best_m, {"units": "1", "long_name": "argmin m of J"}),
            "best_alpha": (("wslr",), best_alpha, {"units": "1", "long_name": "argmin alpha of J"}),
        },
        coords={
            "wslr": ("wslr", list(METHODS), {"units": "1", "long_name": "WSLR reading"}),
            "m": ("m", np.asarray(m_values), {"units": "1", "long_name": "number of joint nodes m"}),
            "alpha": ("alpha", alphas, {"units": "1", "long_name": "geometric weight parameter alpha"}),
        },
    )


def best_weights(ds: xr.Dataset, method: str) -> tuple[int, float]:
    """(m*, α*) of a cost dataset for a WSLR method.

    Parameters
    ----------
    ds : xarray.Dataset
        A cost dataset of :func:`cost_grid` (variables ``best_m``, ``best_alpha`` over ``wslr``).
    method : str
        WSLR reading, ``regression`` or ``mean`` (usually ``scn.joint.wslr``).

    Returns
    -------
    m : int
        Cost-minimizing number of joint nodes.
    alpha : float
        Cost-minimizing geometric weight parameter α [1], in (0, 1).

    Raises
    ------
    KeyError
        If ``method`` is not on the dataset's ``wslr`` coordinate.
    """
    return int(ds["best_m"].sel(wslr=method)), float(ds["best_alpha"].sel(wslr=method))


def one_se_settings(ds: xr.Dataset, method: str) -> list[tuple[int, float | None]]:
    """The distinct (m, α) within one standard error of the minimum for a WSLR method; for
    m = 1 the weights do not depend on α, so it is one setting (α None).

    Parameters
    ----------
    ds : xarray.Dataset
        A cost dataset of :func:`cost_grid` (variable ``within_1se`` over ``wslr``, ``m`` and
        ``alpha``).
    method : str
        WSLR reading, ``regression`` or ``mean`` (usually ``scn.joint.wslr``).

    Returns
    -------
    list of tuple of (int, float or None)
        The settings (m, α) with J ≤ J_min + SE(J_min), α [1], in the order of the ``m`` and
        ``alpha`` coordinates; m = 1 appears once, as ``(1, None)``, if any of its α is within.

    Raises
    ------
    KeyError
        If ``method`` is not on the dataset's ``wslr`` coordinate.
    """
    w = ds["within_1se"].sel(wslr=method)
    out: list[tuple[int, float | None]] = []
    for m in ds["m"].values:
        row = w.sel(m=m).values
        if int(m) == 1:
            if row.any():
                out.append((1, None))
        else:
            out += [(int(m), float(a)) for a in ds["alpha"].values[row]]
    return out
