"""Rates per (input, policy) with clustered Wilson intervals, the σ crossover, key numbers."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

from railradio.keynumbers import KeySpec
from railradio.stats import clustered_mean, clustered_rate


def summarize(shards: Sequence[xr.Dataset]) -> xr.Dataset:
    """Success / ping-pong rates (95 % Wilson, clustered n_eff), mean delay and the RMS of
    the position error actually fed, per (input, policy), from the concatenated shards.

    Parameters
    ----------
    shards : sequence of xarray.Dataset
        Datasets of :func:`railradio.chain.sim.simulate_blocks` (disjoint runs, the same
        inputs, policies and nodes), concatenated along ``run``.

    Returns
    -------
    xarray.Dataset
        Over (input, policy): ``success``, ``pingpong`` [1] with ``_lo``, ``_hi`` (95 %
        interval bounds) and ``_se`` (cluster-robust standard error), ``delay_ms`` [ms] (mean
        delay of the successful handovers) and ``delay_ms_se``; over (input): ``err_mean_m``,
        ``err_rms_m``, ``err_std_m`` [m] of the position error fed; coordinates ``input``,
        ``sigma_m`` [m] (NaN for nr inputs), ``policy``; scalars ``speed_kmh`` [km/h] and
        ``n_handovers`` [1] (node handovers per (input, policy)).
    """
    ds = xr.concat(list(shards), dim="run", data_vars="minimal", coords="minimal", compat="override")
    labels, policies = list(ds["input"].values), list(ds["policy"].values)
    out: dict[str, np.ndarray] = {}
    names = [
        "success",
        "success_lo",
        "success_hi",
        "success_se",
        "pingpong",
        "pingpong_lo",
        "pingpong_hi",
        "pingpong_se",
        "delay_ms",
        "delay_ms_se",
    ]
    for n in names:
        out[n] = np.full((len(labels), len(policies)), np.nan)
    for i, lab in enumerate(labels):
        for j, p in enumerate(policies):
            for rate in ("success", "pingpong"):
                r = clustered_rate(ds[rate].sel(input=lab, policy=p).values.astype(float))
                out[rate][i, j], out[f"{rate}_lo"][i, j], out[f"{rate}_hi"][i, j], out[f"{rate}_se"][i, j] = (
                    r["p"],
                    r["lo"],
                    r["hi"],
                    r["se"],
                )
            m = clustered_mean(1e3 * ds["delay_s"].sel(input=lab, policy=p).values)
            out["delay_ms"][i, j], out["delay_ms_se"][i, j] = m["mean"], m["se"]
    attrs = {
        "success": ("1", "handover success rate"),
        "pingpong": ("1", "ping-pong rate"),
        "delay_ms": ("ms", "mean handover delay (successful)"),
    }
    data = {}
    for n, arr in out.items():
        base = n.split("_")[0] if not n.startswith("delay") else "delay_ms"
        units, ln = attrs[base]
        suffix = {"lo": ": 95% CI lower bound", "hi": ": 95% CI upper bound", "se": ": standard error"}
        data[n] = (("input", "policy"), arr, {"units": units, "long_name": ln + suffix.get(n.rsplit("_", 1)[-1], "")})
    em = ds["err_mean_m"].mean("run").values
    ems = ds["err_ms_m2"].mean("run").values
    data["err_mean_m"] = (("input",), em, {"units": "m", "long_name": "mean along-track position error fed"})
    data["err_rms_m"] = (("input",), np.sqrt(ems), {"units": "m", "long_name": "RMS along-track position error fed"})
    data["err_std_m"] = (
        ("input",),
        np.sqrt(np.maximum(ems - em * em, 0.0)),
        {"units": "m", "long_name": "std of the along-track position error fed"},
    )
    res = xr.Dataset(data, coords={"input": ds["input"], "sigma_m": ds["sigma_m"], "policy": ds["policy"]})
    res["speed_kmh"] = ds["speed_kmh"]
    res["n_handovers"] = xr.Variable(
        (),
        float(ds["success"].sel(input=labels[0], policy=policies[0]).size),
        {"units": "1", "long_name": "node handovers per (input, policy)"},
    )
    return res


def crossover(sigmas_m, p_policy, p_ref: float) -> tuple[float, str]:
    """First σ at which ``p_policy(σ)`` falls to ``p_ref``, linearly interpolated.

    Returns (σ*, status): ``found`` (σ* finite), ``above`` (p_policy > p_ref at every σ of
    the grid: the crossover lies beyond the largest σ, σ* = NaN) or ``never`` (p_policy ≤
    p_ref already at the smallest σ, σ* = NaN).

    Parameters
    ----------
    sigmas_m : array_like of float
        Gauss–Markov σ grid [m], 1-D, strictly ascending, at least 2 values.
    p_policy : array_like of float
        The policy's rate at each σ (its success rate or a 95 % bound of it) [1], finite,
        the shape of ``sigmas_m``.
    p_ref : float
        The reference rate (A3's success rate or a 95 % bound of it) [1], finite.

    Returns
    -------
    sigma_star_m : float
        The crossover σ* [m], interpolated linearly between the last σ above ``p_ref`` and
        the first at or below it; NaN unless ``status`` is ``found``.
    status : str
        ``"found"``, ``"above"`` or ``"never"`` (see above).

    Raises
    ------
    ValueError
        If ``sigmas_m`` and ``p_policy`` are not 1-D of equal length >= 2, ``sigmas_m`` is not
        strictly ascending, or ``p_policy`` or ``p_ref`` is not finite.
    """
    s = np.asarray(sigmas_m, dtype=float)
    p = np.asarray(p_policy, dtype=float)
    if s.ndim != 1 or s.size < 2 or s.shape != p.shape:
        raise ValueError(f"sigmas_m and p_policy must be 1-D of equal length >= 2, got {s.shape}, {p.shape}")
    if np.any(np.diff(s) <= 0):
        raise ValueError("sigmas_m must be strictly ascending")
    if not (np.all(np.isfinite(p)) and math.isfinite(p_ref)):
        raise ValueError("p_policy and p_ref must be finite")
    d = p - p_ref
    if d[0] <= 0:
        return math.nan, "never"
    below = np.flatnonzero(d <= 0)
    if below.size == 0:
        return math.nan, "above"
    k = int(below[0])
    s0, s1, d0, d1 = s[k - 1], s[k], d[k - 1], d[k]
    return float(s0 + (s1 - s0) * d0 / (d0 - d1)), "found"


STATUS_CODE = {"found": 0.0, "above": 1.0, "never": -1.0}


def _put(
    out: dict[str, Any], name: str, unit: str, desc: str, value: float | None, se: float | None = None, digits: int = 3
) -> None:
    """Add key ``name`` to ``out`` (a non-finite value or standard error: null)."""
    out[name] = KeySpec(name, unit, desc, digits=digits).entry(
        None if value is None or not math.isfinite(value) else float(value),
        None if se is None or not math.isfinite(se) else float(se),
    )


def key_numbers(summ: xr.Dataset, nr_stats: dict[str, dict[str, float]], figure_max_sigma_m: float) -> dict[str, Any]:
    """Key numbers ``chain.*`` (the chain is ours: no source value).

    Parameters
    ----------
    summ : xarray.Dataset
        The chain summary (:func:`summarize`); A3's reference is its Gauss–Markov input of
        the smallest σ.
    nr_stats : dict of str to dict
        nr filter -> its statistics (:func:`railradio.chain.nr_error.nr_statistics`), for
        every ``nr_<filter>`` input of ``summ``.
    figure_max_sigma_m : float
        Largest σ of the figure's left panel [m]; the ``*_fig`` keys cover σ <= it.

    Returns
    -------
    dict of str to dict
        Key name -> its JSON entry (:meth:`railradio.keynumbers.KeySpec.entry`; a non-finite
        value or standard error is null): A3, joint and distance success and ping-pong rates
        [1], the Gauss–Markov σ crossovers with A3 [m] and their status (0 found, 1 above,
        -1 never), the nr inputs' error statistics [m] and shares [1], ``chain.sigma_max_m``
        [m] and ``chain.n_handovers`` [1].

    Raises
    ------
    ValueError
        If ``summ`` holds fewer than 2 Gauss–Markov σ, or a success rate on the σ grid or
        A3's is not finite (:func:`crossover`).
    KeyError
        If ``nr_stats`` lacks the filter of an ``nr_<filter>`` input.
    """
    out: dict[str, Any] = {}
    v = float(summ["speed_kmh"])
    gm = summ.where(np.isfinite(summ["sigma_m"]), drop=True).sortby("sigma_m")
    a3 = summ["success"].sel(policy="a3")
    a3_ref = float(a3.sel(input=gm["input"].values[0]))
    _a3_keys(out, summ, gm, v, a3, a3_ref)
    _nr_input_keys(out, summ, nr_stats, v, a3_ref)
    for p in ("joint", "distance"):
        _policy_sigma_keys(out, summ, gm, p, a3_ref, figure_max_sigma_m)
    _comparison_keys(out, summ, gm, figure_max_sigma_m)
    return out


def _a3_keys(out: dict[str, Any], summ: xr.Dataset, gm: xr.Dataset, v: float, a3: xr.DataArray, a3_ref: float) -> None:
    """A3 (position-free reference): success and ping-pong at speed v [km/h], and the spread
    of its success over the position inputs."""
    _put(
        out,
        f"chain.a3.success.v{v:g}",
        "1",
        f"A3 success at {v:g} km/h (position-free reference)",
        a3_ref,
        float(summ["success_se"].sel(policy="a3", input=gm["input"].values[0])),
        4,
    )
    _put(
        out,
        "chain.a3.success_spread",
        "1",
        "max − min of A3 success over all position inputs (0: A3 ignores position)",
        float(a3.max() - a3.min()),
    )
    _put(
        out,
        f"chain.a3.pingpong.v{v:g}",
        "1",
        f"A3 ping-pong at {v:g} km/h",
        float(summ["pingpong"].sel(policy="a3", input=gm["input"].values[0])),
        None,
        4,
    )


def _nr_input_keys(
    out: dict[str, Any], summ: xr.Dataset, nr_stats: dict[str, dict[str, float]], v: float, a3_ref: float
) -> None:
    """Per nr position input: joint/distance rates, success minus A3's, and the input's
    error statistics (``nr_stats[filt]``)."""
    for filt in [str(i)[3:] for i in summ["input"].values if str(i).startswith("nr_")]:
        lab = f"nr_{filt}"
        for p in ("joint", "distance"):
            for rate in ("success", "pingpong"):
                _put(
                    out,
                    f"chain.nr_{filt}.{p}.{rate}.v{v:g}",
                    "1",
                    f"{p} {rate} at {v:g} km/h with the nr {filt.upper()} position",
                    float(summ[rate].sel(input=lab, policy=p)),
                    float(summ[f"{rate}_se"].sel(input=lab, policy=p)),
                    4,
                )
            _put(
                out,
                f"chain.nr_{filt}.{p}.success_minus_a3",
                "1",
                f"{p} success with nr {filt.upper()} position minus A3's",
                float(summ["success"].sel(input=lab, policy=p)) - a3_ref,
            )
        _put(
            out,
            f"chain.nr_{filt}.sigma_eff_m",
            "m",
            f"RMS along-track error of the nr {filt.upper()} input as fed (bootstrap)",
            float(summ["err_rms_m"].sel(input=lab)),
        )
        st = nr_stats[filt]
        _put(
            out,
            f"chain.nr_{filt}.err_m.mean",
            "m",
            f"mean signed along-track error of the nr {filt.upper()} (source epochs)",
            st["mean"],
        )
        _put(
            out,
            f"chain.nr_{filt}.err_m.p95",
            "m",
            f"95th percentile of |along-track error| of the nr {filt.upper()}",
            st["p95"],
        )
        _put(
            out,
            f"chain.nr_{filt}.err_m.rms",
            "m",
            f"RMS along-track error of the nr {filt.upper()} (source epochs)",
            st["rms"],
        )
        _put(
            out,
            f"chain.nr_{filt}.outage_share",
            "1",
            "share of used nr epochs with no tracker output (filled: hold + drift)",
            st["outage_share"],
        )
        _put(
            out,
            f"chain.nr_{filt}.nofix_share",
            "1",
            "share of used nr epochs without any detected RRH (EKF coasts)",
            st["nofix_share"],
        )
        _put(
            out,
            f"chain.nr_{filt}.epochs",
            "1",
            "nr epochs within the speed window, pooled over realizations",
            st["epochs"],
        )


def _policy_sigma_keys(
    out: dict[str, Any], summ: xr.Dataset, gm: xr.Dataset, p: str, a3_ref: float, figure_max_sigma_m: float
) -> None:
    """Policy ``p`` along the Gauss–Markov σ sweep ``gm``: the crossover with A3 (and of the
    95 % bounds), whether it beats A3 in the figure's range, success at σ = 0, 2, the
    figure's largest σ [m], and the drop over the figure's range."""
    sig = gm["sigma_m"].values
    ps = gm["success"].sel(policy=p).values
    s_star, status = crossover(sig, ps, a3_ref)
    lo, _ = crossover(
        sig,
        gm["success_lo"].sel(policy=p).values,
        float(summ["success_hi"].sel(policy="a3", input=gm["input"].values[0])),
    )
    hi, _ = crossover(
        sig,
        gm["success_hi"].sel(policy=p).values,
        float(summ["success_lo"].sel(policy="a3", input=gm["input"].values[0])),
    )
    pre = "chain" if p == "joint" else "chain.distance"
    _put(
        out,
        f"{pre}.sigma_crossover_m",
        "m",
        f"Gauss–Markov σ at which {p} success falls to A3's (interpolated; null: status ≠ 0)",
        s_star,
    )
    _put(out, f"{pre}.sigma_crossover_m_lo", "m", f"crossover of {p}'s lower 95% bound with A3's upper bound", lo)
    _put(out, f"{pre}.sigma_crossover_m_hi", "m", f"crossover of {p}'s upper 95% bound with A3's lower bound", hi)
    _put(
        out,
        f"{pre}.sigma_crossover_status",
        "1",
        "0: crossover found; 1: beats A3 at every σ swept; −1: never beats A3",
        STATUS_CODE[status],
    )
    in_fig = sig <= figure_max_sigma_m
    _put(
        out,
        f"chain.{p}.beats_a3_all_sigma_fig",
        "1",
        f"1 if {p}'s lower 95% bound exceeds A3's upper bound at every σ ≤ {figure_max_sigma_m:g} m",
        float(
            np.all(
                gm["success_lo"].sel(policy=p).values[in_fig]
                > float(summ["success_hi"].sel(policy="a3", input=gm["input"].values[0]))
            )
        ),
    )
    for s in (0.0, 2.0, figure_max_sigma_m):
        if s in sig:
            lab = gm["input"].values[list(sig).index(s)]
            _put(
                out,
                f"chain.{p}.success.sigma{s:g}",
                "1",
                f"{p} success at Gauss–Markov σ = {s:g} m",
                float(summ["success"].sel(input=lab, policy=p)),
                float(summ["success_se"].sel(input=lab, policy=p)),
                4,
            )
    _put(
        out,
        f"chain.{p}.success_drop_fig",
        "1",
        f"{p} success at σ = 0 minus at σ = {figure_max_sigma_m:g} m",
        float(ps[0] - ps[in_fig][-1]),
    )


def _comparison_keys(out: dict[str, Any], summ: xr.Dataset, gm: xr.Dataset, figure_max_sigma_m: float) -> None:
    """Distance against joint in the figure's range, the joint crossover over each nr
    input's RMS error, the largest σ swept and the handover count (after the crossovers)."""
    sig = gm["sigma_m"].values
    in_fig = sig <= figure_max_sigma_m
    _put(
        out,
        "chain.distance_minus_joint_min_fig",
        "1",
        f"smallest distance-minus-joint success difference over σ ≤ {figure_max_sigma_m:g} m (> 0: distance better "
        f"everywhere)",
        float(
            np.min(
                gm["success"].sel(policy="distance").values[in_fig] - gm["success"].sel(policy="joint").values[in_fig]
            )
        ),
    )
    s_star = out["chain.sigma_crossover_m"]["value"]
    for filt in [str(i)[3:] for i in summ["input"].values if str(i).startswith("nr_")]:
        eff = float(summ["err_rms_m"].sel(input=f"nr_{filt}"))
        _put(
            out,
            f"chain.nr_{filt}.sigma_margin",
            "1",
            f"joint crossover σ over the RMS error of the nr {filt.upper()} input",
            None if s_star is None or eff <= 0 else s_star / eff,
        )
    _put(out, "chain.sigma_max_m", "m", "largest Gauss–Markov σ swept", float(sig[-1]))
    _put(out, "chain.n_handovers", "1", "node handovers per (input, policy)", float(summ["n_handovers"]))
