"""Chained handover runs: the handover engine's blocks with the position input replaced.

Every input sees the handover sweep's own draws at the chain speed (blocks 0…n_blocks−1 of
stream ``sweep``: the same crossings, shadowing and measurement noise as the handover
study; common random numbers across inputs).  Inputs:

- ``gm_<σ>``: first-order Gauss–Markov along-track error, stationary std σ, correlation time
  ``gm_corr_s``, **untruncated** — the swept σ is then the error's true std, and the nr input
  (whose tails are its own) can be placed on the same axis at its RMS.  The white noise is the
  block's ``gnss_white`` for every σ, so the σ curves are paired.
- ``nr_<filter>``: the nr tracker's along-track error, block-bootstrapped
  (:mod:`railradio.chain.nr_error`) with its own generator,
  ``spawn_key("handover", stable_id("chain"), stable_id(speed), stable_id(filter), block)``.

A3 does not read the position; it is nevertheless run on every input (its invariance is
then a measured fact, not an assumption).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import xarray as xr

from railradio.chain.nr_error import ErrorSeries, bootstrap
from railradio.handover.model import build_context, draw_block
from railradio.handover.params import Scenario
from railradio.handover.policies import make_policy, run_policy
from railradio.handover.radio import ar1_coefficient, ar1_process
from railradio.handover.train import kinematics
from railradio.rng import make_rng, spawn_key, stable_id

POLICIES = ("joint", "distance", "a3")
OUTCOMES = {
    "success": ("1", "1 if the handover succeeded"),
    "pingpong": ("1", "1 if commanded back to the previous cell within the ping-pong window"),
    "delay_s": ("s", "first command to completion incl. retries (NaN: failed)"),
}


def gm_label(sigma_m: float) -> str:
    """Input label of a Gauss–Markov σ: ``gm_2`` or ``gm_7.5``.

    Parameters
    ----------
    sigma_m : float
        Stationary standard deviation σ of the Gauss–Markov error [m].

    Returns
    -------
    str
        ``"gm_"`` followed by σ formatted with ``{:g}``.
    """
    return f"gm_{float(sigma_m):g}"


def gm_error_m(white: np.ndarray, sigma_m: float, corr_s: float, period_s: float) -> np.ndarray:
    """Untruncated first-order Gauss–Markov error [m] from standard normals [..., K].

    Parameters
    ----------
    white : numpy.ndarray of float
        Standard normal draws [1], shape [..., K]; the process runs along the last axis
        (e.g. a block's ``gnss_white``, [B runs, K handover samples]).
    sigma_m : float
        Stationary standard deviation σ of the error [m], finite, >= 0.
    corr_s : float
        Correlation time of the process [s], > 0 (unused when ``sigma_m`` is 0).
    period_s : float
        Time between successive samples along the last axis [s], > 0.

    Returns
    -------
    numpy.ndarray of float
        Along-track position error [m], the shape of ``white``: a stationary AR(1) process
        with coefficient exp(-period_s/corr_s) and standard deviation σ (zeros for σ = 0).

    Raises
    ------
    ValueError
        If ``sigma_m`` is negative or not finite, or (with ``sigma_m`` > 0) ``corr_s`` <= 0
        or ``period_s`` = 0 (an AR(1) coefficient of 1).
    """
    if not sigma_m >= 0 or not math.isfinite(sigma_m):
        raise ValueError(f"sigma_m must be a finite number >= 0, got {sigma_m!r}")
    if sigma_m == 0.0:
        return np.zeros(np.shape(white))
    return ar1_process(white, ar1_coefficient(period_s, corr_s), sigma_m)


def nr_rng(seed: int, speed_kmh: float, filt: str, block: int) -> np.random.Generator:
    """Generator of the nr bootstrap of one block (its own stream beside the handover's).

    Parameters
    ----------
    seed : int
        The config's master seed, >= 0.
    speed_kmh : float
        Train speed of the chain [km/h]; keyed as a float.
    filt : str
        nr tracker (filter) name, e.g. ``"ekf"``.
    block : int
        Block index, >= 0.

    Returns
    -------
    numpy.random.Generator
        The generator of ``(seed, spawn_key("handover", stable_id("chain"),
        stable_id(float(speed_kmh)), stable_id(filt), block))``.

    Raises
    ------
    ValueError
        If ``seed`` or ``block`` is not a non-negative integer.
    """
    return make_rng(
        seed, spawn_key("handover", stable_id("chain"), stable_id(float(speed_kmh)), stable_id(filt), int(block))
    )


def simulate_block(
    scn: Scenario,
    speed_kmh: float,
    seed: int,
    block: int,
    n_runs: int,
    sigmas_m,
    gm_corr_s: float,
    nr: dict[str, ErrorSeries],
) -> dict[str, dict]:
    """Outcomes per input label -> policy -> name -> [B, N] array, plus ``err`` -> [B, K] error.

    Parameters
    ----------
    scn : Scenario
        The handover scenario (``railradio.handover.params``), with the joint policy's
        weights set.
    speed_kmh : float
        Train speed [km/h].
    seed : int
        The config's master seed, >= 0.
    block : int
        Block index (>= 0) of the handover sweep's stream ``sweep``; selects the draws.
    n_runs : int
        Crossings B in the block, >= 1.
    sigmas_m : iterable of float
        Gauss–Markov σ grid [m], each finite and >= 0; one input ``gm_<σ>`` each.
    gm_corr_s : float
        Correlation time of the Gauss–Markov error [s], > 0.
    nr : dict of str to ErrorSeries
        nr filter name -> its pooled error series (:func:`railradio.chain.nr_error.series_from_runs`);
        one input ``nr_<filter>`` each (may be empty).

    Returns
    -------
    dict
        Input label (``gm_<σ>`` by :func:`gm_label`, then ``nr_<filter>``) -> {policy
        (:data:`POLICIES`) -> {outcome (:data:`OUTCOMES`: ``success``, ``pingpong`` [1],
        ``delay_s`` [s]) -> float array [B runs, N nodes]}, ``"err"`` -> along-track position
        error fed [m], [B, K handover samples]}.

    Raises
    ------
    ValueError
        If a σ is negative or not finite, ``gm_corr_s`` <= 0 (with a σ > 0), ``n_runs`` < 1,
        ``block`` < 0 or ``seed`` is not a non-negative integer.
    """
    kin = kinematics(scn, speed_kmh)
    draws = draw_block(seed, speed_kmh, block, n_runs, kin, scn.train.n_nodes)
    ctx = build_context(scn, kin, draws)
    inputs = {gm_label(s): gm_error_m(draws.gnss_white, float(s), gm_corr_s, kin.period_s) for s in sigmas_m}
    for filt, series in nr.items():
        inputs[f"nr_{filt}"] = bootstrap(
            series, n_runs, kin.n_samples, kin.period_s, nr_rng(seed, speed_kmh, filt, block)
        )
    out = {}
    for label, err in inputs.items():
        c = dataclasses.replace(ctx, gnss_err_m=err, _cache={})
        res = {p: run_policy(make_policy(p), c) for p in POLICIES}
        out[label] = {p: {k: np.asarray(res[p][k][1], dtype=float) for k in OUTCOMES} for p in POLICIES}
        out[label]["err"] = err
    return out


def simulate_blocks(
    scn: Scenario,
    speed_kmh: float,
    seed: int,
    blocks: range,
    n_runs: int,
    sigmas_m,
    gm_corr_s: float,
    nr: dict[str, ErrorSeries],
) -> xr.Dataset:
    """Per-handover outcomes over (input, policy, run, node) and the per-run error moments.

    Parameters
    ----------
    scn : Scenario
        The handover scenario (``railradio.handover.params``), with the joint policy's
        weights set.
    speed_kmh : float
        Train speed [km/h].
    seed : int
        The config's master seed, >= 0.
    blocks : range
        The blocks of the shard (contiguous, non-empty), each run by :func:`simulate_block`.
    n_runs : int
        Crossings per block (the config's ``runs_per_block``), >= 1.
    sigmas_m : iterable of float
        Gauss–Markov σ grid [m], each finite and >= 0; one input ``gm_<σ>`` each.
    gm_corr_s : float
        Correlation time of the Gauss–Markov error [s], > 0.
    nr : dict of str to ErrorSeries
        nr filter name -> its pooled error series (:func:`railradio.chain.nr_error.series_from_runs`);
        one input ``nr_<filter>`` each (may be empty).

    Returns
    -------
    xarray.Dataset
        Over (input, policy, run, node): ``success``, ``pingpong`` [1] (int8, 0/1) and
        ``delay_s`` [s] (NaN: failed); over (input, run): ``err_mean_m`` [m] and ``err_ms_m2``
        [m²], the per-crossing mean and mean square of the position error fed.  Coordinates
        ``input``, ``sigma_m`` [m] (over input; NaN for nr inputs), ``policy``, ``run``
        (global crossing index block·n_runs + j), ``node`` (1 = head); scalar ``speed_kmh``
        [km/h].

    Raises
    ------
    ValueError
        If ``blocks`` is empty, or as :func:`simulate_block`.
    """
    if len(blocks) == 0:
        raise ValueError("blocks must not be empty")
    parts = [simulate_block(scn, speed_kmh, seed, b, n_runs, sigmas_m, gm_corr_s, nr) for b in blocks]
    labels = list(parts[0])
    data = {}
    for name, (units, long_name) in OUTCOMES.items():
        arr = np.stack(
            [np.stack([np.concatenate([pt[lab][p][name] for pt in parts]) for p in POLICIES]) for lab in labels]
        )
        data[name] = (
            ("input", "policy", "run", "node"),
            arr.astype(np.int8) if name != "delay_s" else arr,
            {"units": units, "long_name": long_name},
        )
    err = [np.concatenate([pt[lab]["err"] for pt in parts]) for lab in labels]
    data["err_mean_m"] = (
        ("input", "run"),
        np.stack([e.mean(axis=1) for e in err]),
        {"units": "m", "long_name": "per-crossing mean along-track position error"},
    )
    data["err_ms_m2"] = (
        ("input", "run"),
        np.stack([np.mean(e * e, axis=1) for e in err]),
        {"units": "m2", "long_name": "per-crossing mean square along-track position error"},
    )
    sig = [float(lab[3:]) if lab.startswith("gm_") else math.nan for lab in labels]
    runs = np.arange(blocks[0] * n_runs, blocks[-1] * n_runs + n_runs)
    coords = {
        "input": (
            "input",
            labels,
            {"units": "1", "long_name": "position input (gm_<sigma>: Gauss-Markov; nr_<filter>)"},
        ),
        "sigma_m": ("input", np.array(sig), {"units": "m", "long_name": "Gauss-Markov error std (NaN: nr input)"}),
        "policy": ("policy", list(POLICIES), {"units": "1", "long_name": "handover policy"}),
        "run": ("run", runs, {"units": "1", "long_name": "global crossing index (block*runs_per_block + j)"}),
        "node": ("node", np.arange(scn.train.n_nodes) + 1, {"units": "1", "long_name": "relay-AP node (1 = head)"}),
    }
    ds = xr.Dataset(data, coords=coords)
    ds["speed_kmh"] = xr.Variable((), float(speed_kmh), {"units": "km/h", "long_name": "train speed"})
    return ds
