"""Key numbers of the handover study (docs/model/handover.md §7), ours beside the source's claims."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from railradio.handover.bounds import (
    first_attempt_success_at_centre,
    gap_sigma_db,
    gap_window_db,
    t304_gap_hi_db,
    t304_success_at_centre,
)
from railradio.handover.cost import one_se_settings
from railradio.keynumbers import KeySpec

POLICIES = ("joint", "a3", "distance")
"""The source's three policies (its claims compare these)."""
ALL_POLICIES = (*POLICIES, "a3_rail")
"""Every policy of the study: the source's three and A3 as railways tune it."""
STAGE_SPEEDS = (100, 350, 500)
"""Speeds [km/h] of the failure-stage keys (the sweep's ends and the source's 350)."""
STAGE_METRICS = {
    "success": ("1", "handover success (completions over commands)", 4),
    "too_late": ("1", "share of handovers too late (the serving side failed; re-established in the target)", 4),
    "too_early": ("1", "share of handovers too early (access or the new link failed; re-established in the source)", 4),
    "other_rlf": ("1", "share of failures re-established in the cell that failed (not mobility failures)", 4),
    "t310_at_command": ("1", "share of commands that came while the serving link's T310 ran", 4),
    "interruption_ms_median": ("ms", "median interruption (command to completion, re-establishment included)", 3),
    "interruption_ms_p95": ("ms", "95th percentile of the interruption (command to completion)", 3),
}
"""The failure-stage keys per policy and speed (``handover.<policy>.<metric>.v<speed>``)."""


def _spec(name, unit, desc, src=None, rel=None, digits=3):
    return KeySpec(name, unit, desc, src, rel, digits)


SPECS = {
    s.name: s
    for s in [
        _spec(
            "handover.best_m",
            "1",
            "number of joint nodes m minimizing the cost (config WSLR reading; "
            "the settings within one standard error are handover.cost.set_1se.*)",
            3,
            "=",
        ),
        _spec(
            "handover.best_alpha",
            "1",
            "geometric weight parameter alpha at the cost minimum (reported only "
            "when m* > 1: for m = 1 the weights do not depend on alpha)",
        ),
        _spec(
            "handover.cost.set_1se.m_min",
            "1",
            "smallest m among the settings within one standard error of the minimum cost (config WSLR reading)",
        ),
        _spec(
            "handover.cost.set_1se.m_max",
            "1",
            "largest m among the settings within one standard error of the minimum cost",
        ),
        _spec(
            "handover.cost.set_1se.n_settings",
            "1",
            "distinct (m, alpha) settings within one standard error of the minimum cost (m = 1 counts once)",
        ),
        _spec("handover.cost.set_1se.n_grid", "1", "distinct (m, alpha) settings searched (m = 1 counts once)"),
        _spec("handover.cost.min", "1", "minimum cost J = E[C/N] + E[F]", digits=3),
        _spec("handover.cost.m3_minus_best", "1", "cost at m = 3 (best alpha) minus the minimum cost"),
        *[
            _spec(
                f"handover.cost.full_grid_gain.m{m}",
                "1",
                f"m = {m}: min cost over the geometric family minus over the full per-element grid (same runs; "
                f"the grid's min over thousands of noisy estimates is biased low, so this gain is biased high)",
            )
            for m in (2, 3, 4)
        ],
        _spec("handover.cost.min_se", "1", "Monte Carlo standard error of the minimum cost (the one-SE threshold)"),
        *[
            _spec(f"handover.cost.full_grid_gain_se.m{m}", "1", f"paired standard error of full_grid_gain.m{m}")
            for m in (2, 3, 4)
        ],
        *[
            _spec(f"handover.cost.min.m{m}", "1", f"min over alpha of the cost at m = {m} (config WSLR reading)")
            for m in range(1, 7)
        ],
        _spec(
            "handover.joint.success.v350",
            "1",
            "joint decision: handover success rate at 350 km/h",
            0.9975,
            "≥",
            digits=4,
        ),
        _spec(
            "handover.joint.success.min_v300_380",
            "1",
            "joint decision: lowest success rate over 300-380 km/h",
            0.9975,
            "≥",
            digits=4,
        ),
        _spec("handover.a3.success.v350", "1", "A3: handover success rate at 350 km/h", 0.995, "<", digits=4),
        _spec("handover.distance.success.v350", "1", "distance trigger: success rate at 350 km/h", digits=4),
        _spec("handover.a3.delay_ms.v250", "ms", "A3: mean handover delay at 250 km/h", 45.0, ">"),
        _spec(
            "handover.joint.delay_ms.v350",
            "ms",
            "joint decision: mean handover delay at 350 km/h (source: meets the 45 ms requirement)",
            45.0,
            "≤",
        ),
        _spec("handover.distance.delay_ms.v350", "ms", "distance trigger: mean handover delay at 350 km/h"),
        _spec("handover.joint.pingpong.v350", "1", "joint decision: ping-pong rate at 350 km/h (0 by construction)"),
        _spec("handover.a3.pingpong.v350", "1", "A3: ping-pong rate at 350 km/h"),
        _spec("handover.distance.pingpong.v350", "1", "distance trigger: ping-pong rate at 350 km/h"),
        _spec(
            "handover.claim.joint_pingpong_lowest_frac",
            "1",
            "share of speeds where the joint ping-pong rate is strictly the lowest of the three: the "
            "upper 95% bound of joint below the lower 95% bound of both A3 and distance (a tie is not lower)",
            1.0,
            "=",
        ),
        _spec(
            "handover.claim.pingpong_tie_frac",
            "1",
            "share of speeds where the joint ping-pong rate is not separable from another policy's "
            "(95% intervals overlap)",
        ),
        _spec(
            "handover.claim.joint_gap_lowest_frac",
            "1",
            "share of speeds where the joint mean |RSRP-GAP| is the lowest of the three",
            1.0,
            "=",
        ),
        _spec("handover.joint.rsrp_gap_db.v350", "dB", "joint decision: mean |RSRP-GAP| at completion, 350 km/h"),
        _spec("handover.a3.rsrp_gap_db.v350", "dB", "A3: mean |RSRP-GAP| at completion, 350 km/h"),
        _spec("handover.distance.rsrp_gap_db.v350", "dB", "distance trigger: mean |RSRP-GAP| at completion, 350 km/h"),
        _spec("handover.joint.success.v100", "1", "joint decision: success rate at 100 km/h", digits=4),
        _spec(
            "handover.a3.success.v100", "1", "A3: success rate at 100 km/h (railway requirement: >= 0.995)", digits=4
        ),
        _spec("handover.distance.success.v100", "1", "distance trigger: success rate at 100 km/h", digits=4),
        *[
            _spec(
                f"handover.{pol}.delay_all_ms.v{v}",
                "ms",
                f"{pol}: mean command-to-completion time over all handovers at {v} km/h (failed attempts, "
                f"retries and re-establishment included)"
                + (" (source: A3 > 45 ms above 250 km/h)" if pol == "a3" and v == 350 else ""),
                45.0 if pol == "a3" and v == 350 else None,
                ">" if pol == "a3" and v == 350 else None,
            )
            for pol in ("joint", "a3", "distance")
            for v in (100, 250, 350)
        ],
        *[
            _spec(
                f"handover.{pol}.delay_trigger_ms.v{v}",
                "ms",
                f"{pol}: mean trigger-to-completion time over all handovers at {v} km/h (A3: from the start "
                f"of its time-to-trigger)",
            )
            for pol in ("joint", "a3", "distance")
            for v in (100, 250, 350)
        ],
        *[
            _spec(f"handover.{pol}.{metric}.v{v}", unit, f"{pol}: {desc} at {v} km/h", digits=digits)
            for pol in ALL_POLICIES
            for v in STAGE_SPEEDS
            for metric, (unit, desc, digits) in STAGE_METRICS.items()
            if f"handover.{pol}.{metric}.v{v}"
            not in {
                f"handover.{p}.success.v{w}" for p in POLICIES for w in (100, 350)
            }  # those are above, with the source's values
        ],
        *[
            _spec(
                f"handover.{pol}.too_late.rise_100_500",
                "1",
                f"{pol}: too-late share at 500 km/h minus at 100 km/h (same shadowing fields at every speed)",
                digits=4,
            )
            for pol in ALL_POLICIES
        ],
        _spec("handover.gaph_db", "dB", "handover threshold GapH(sigma0)"),
        _spec(
            "handover.bound.first_attempt_success_xc",
            "1",
            "closed form, the earlier instant rule: first-attempt success at the overlap centre, "
            "Phi(hi/sigma_G) - Phi(lo/sigma_G), interference-limited, from the config's eta, Q_out, Q_in, sigma",
            digits=4,
        ),
        _spec(
            "handover.bound.gap_lo_db",
            "dB",
            "closed form: lowest true gap at which an attempt succeeds, Q_out + 10 log10 eta",
        ),
        _spec(
            "handover.bound.gap_hi_db",
            "dB",
            "closed form: highest true gap at which an attempt succeeds, -(Q_in + 10 log10 eta)",
        ),
        _spec(
            "handover.bound.t304_success_xc",
            "1",
            "closed form, rlm rule: target access success at the overlap centre Phi(-(Q_out + 10 log10 eta)"
            "/sigma_G), an upper bound on a first attempt there (radio-link failure not counted)",
            digits=4,
        ),
        _spec(
            "handover.bound.t304_gap_hi_db",
            "dB",
            "closed form, rlm rule: highest true gap at which the target's access succeeds, -(Q_out + 10 log10 eta)",
        ),
        _spec("handover.bound.gap_sigma_db", "dB", "closed form: std of the shadowing gap sigma sqrt(2(1 - rho_st))"),
        _spec("handover.sigma0_db", "dB", "std of the filtered gap-measurement error sigma0"),
        _spec("handover.n_handovers_per_speed", "1", "node handovers simulated per speed point", digits=6),
    ]
}


def _pick(summary: xr.Dataset, policy: str, name: str, speed: float):
    da = summary[name].sel(policy=policy, speed_kmh=speed)
    return float(da)


def pingpong_strictly_lowest(summary: xr.Dataset) -> np.ndarray:
    """bool per speed: the joint ping-pong rate is strictly below A3's and distance's — its
    upper 95% bound below both lower 95% bounds (docs/model/handover.md §7, 'proposed < A3, distance'; a
    policy with zero ping-pong ties with joint's zero and does not count).

    Parameters
    ----------
    summary : xarray.Dataset
        Rates and means per policy and speed (:func:`railradio.handover.summary.metrics_dataset`
        over (``policy``, ``speed_kmh``)) for the policies ``joint``, ``a3`` and ``distance``,
        with the bounds ``pingpong_lo`` and ``pingpong_hi`` [1] of the 95 % interval.

    Returns
    -------
    numpy.ndarray
        bool, one per speed in the order of ``speed_kmh``: True where joint's upper bound is
        below both other policies' lower bounds.
    """
    hi = summary["pingpong_hi"].sel(policy=list(POLICIES)).values
    lo = summary["pingpong_lo"].sel(policy=list(POLICIES)).values
    return hi[0] < lo[1:].min(axis=0)


def _sig_digits(v: float) -> int:
    """Significant digits of v as written (0.64 -> 2, 0.3 -> 1), so it prints as in the config."""
    mant = f"{abs(v):.6e}".split("e")[0].replace(".", "").rstrip("0")
    return max(1, len(mant))


def sens_values(sens: xr.Dataset) -> dict[str, Any]:
    """handover.sens.<case>.value: the numeric value a case sets (for the paper's table;
    exact, from the config via the sensitivity dataset).

    Parameters
    ----------
    sens : xarray.Dataset
        Rates and means per policy and sensitivity ``case``, with ``switch`` (the config key
        ``section.key`` a case changes) and ``value`` (the value it sets, as text) per
        case.

    Returns
    -------
    dict of str to dict
        Key name -> JSON entry (:meth:`railradio.keynumbers.KeySpec.entry`, mc_stderr 0) for
        every case but ``reference`` whose value reads as a number; unit from the key's
        suffix (``_db`` dB, ``_s`` s, ``_m`` m, else 1), significant digits as the config writes
        the value.

    Raises
    ------
    ValueError
        If a value reads as a number that is not finite.
    """
    out = {}
    for var in sens["case"].values:
        if var == "reference":
            continue
        sw = str(sens["switch"].sel(case=var).values)
        try:
            val = float(str(sens["value"].sel(case=var).values))
        except ValueError:
            continue
        name = f"handover.sens.{var}.value"
        short = sw.split(".")[-1]
        unit = next((u for suf, u in (("_db", "dB"), ("_s", "s"), ("_m", "m")) if short.endswith(suf)), "1")
        out[name] = KeySpec(name, unit, f"value of {sw} in the sensitivity case {var}", digits=_sig_digits(val)).entry(
            val, 0.0
        )
    return out


def sens_specs(sens: xr.Dataset) -> dict[str, KeySpec]:
    """Specs of the sensitivity keys handover.sens.<case>.<policy>.<metric>.

    Parameters
    ----------
    sens : xarray.Dataset
        Rates and means per policy and sensitivity ``case``, with ``switch`` and ``value``
        per case, ``affected`` over (``case``, ``policy``) (the case can change the
        policy) and the scalar ``speed_kmh`` [km/h].

    Returns
    -------
    dict of str to KeySpec
        Key name -> spec, for every case (``reference`` included), every policy it affects
        and the metrics ``success``, ``pingpong`` [1], ``delay_ms`` and ``delay_all_ms`` [ms]
        (no ``pingpong`` for ``joint``: zero by construction).
    """
    out = {}
    for var in sens["case"].values:
        sw = str(sens["switch"].sel(case=var).values)
        val = str(sens["value"].sel(case=var).values)
        what = "reference" if var == "reference" else f"{sw} = {val}"
        for pol in sens["policy"].values:
            if not bool(sens["affected"].sel(case=var, policy=pol)):
                continue
            for metric, unit, digits in (
                ("success", "1", 4),
                ("pingpong", "1", 3),
                ("delay_ms", "ms", 3),
                ("delay_all_ms", "ms", 3),
            ):
                if metric == "pingpong" and pol == "joint":
                    continue
                name = f"handover.sens.{var}.{pol}.{metric}"
                out[name] = KeySpec(
                    name,
                    unit,
                    f"sensitivity at {float(sens['speed_kmh']):g} km/h, {what}: {pol} {metric}",
                    digits=digits,
                )
    return out


def _stage_keys(summary: xr.Dataset, speeds: list[float], out: dict, put) -> None:
    """The failure-stage keys (:data:`STAGE_METRICS` at :data:`STAGE_SPEEDS`, per policy) and
    each policy's too-late rise from 100 to 500 km/h (its standard error as if the two
    speeds were independent: conservative, they share the shadowing fields)."""
    for pol in (p for p in ALL_POLICIES if p in summary["policy"].values):
        for metric in STAGE_METRICS:
            for v in STAGE_SPEEDS:
                name = f"handover.{pol}.{metric}.v{v}"
                if name in out or float(v) not in speeds or not np.isfinite(_pick(summary, pol, metric, v)):
                    continue
                se = _pick(summary, pol, f"{metric}_se", v) if f"{metric}_se" in summary else None
                put(name, _pick(summary, pol, metric, v), se)
        if {100.0, 500.0} <= set(speeds) and np.isfinite(_pick(summary, pol, "too_late", 500)):
            rise = _pick(summary, pol, "too_late", 500) - _pick(summary, pol, "too_late", 100)
            se = np.hypot(_pick(summary, pol, "too_late_se", 500), _pick(summary, pol, "too_late_se", 100))
            put(f"handover.{pol}.too_late.rise_100_500", rise, float(se))


def key_numbers(
    summary: xr.Dataset, cost: xr.Dataset, sens: xr.Dataset, gaph_db: float, sigma0_db: float, wslr: str, radio=None
) -> dict[str, Any]:
    """All handover.* key numbers (mc_stderr from the clustered standard errors).

    Parameters
    ----------
    summary : xarray.Dataset
        Rates and means per policy and speed (:func:`railradio.handover.summary.metrics_dataset`
        over (``policy``, ``speed_kmh``), speeds in km/h).
    cost : xarray.Dataset
        The cost dataset of :func:`railradio.handover.cost.cost_grid`.
    sens : xarray.Dataset
        Rates and means per policy and sensitivity ``case`` (with ``switch``, ``value`` and
        the scalar ``speed_kmh`` [km/h]).
    gaph_db : float
        The gap threshold GapH [dB] (from :func:`railradio.handover.band.sigma0_and_gaph`).
    sigma0_db : float
        Standard deviation σ0 of a measured gap [dB].
    wslr : str
        WSLR reading of the study, ``regression`` or ``mean``.
    radio : Radio or None, optional
        The radio parameters; when given, the analytic ``handover.bound.*`` keys are added.

    Returns
    -------
    dict of str to Any
        Key name -> JSON entry (value, unit, source value and relation, description,
        mc_stderr, digits), for ``handover.*`` keys: cost-grid argmin and minima, per-policy
        rates and delays at 100, 250 and 350 km/h, the claim checks, GapH, σ0, bounds and the
        sensitivity keys ``handover.sens.<case>.*``.

    Raises
    ------
    ValueError
        If a key's value is not finite.
    """
    out: dict[str, Any] = {}

    def put(name, value, se=None):
        out[name] = SPECS[name].entry(value, se)

    best_m = int(cost["best_m"].sel(wslr=wslr))
    best_a = float(cost["best_alpha"].sel(wslr=wslr))
    c = cost["cost"].sel(wslr=wslr)
    put("handover.best_m", best_m)
    if best_m > 1:
        put("handover.best_alpha", best_a)
    se_min = float(cost["cost_se"].sel(wslr=wslr, m=best_m, alpha=best_a))
    put("handover.cost.min", float(c.min()), se_min)
    put("handover.cost.min_se", se_min, 0.0)
    if 3 in cost["m"].values:
        put("handover.cost.m3_minus_best", float(c.sel(m=3).min() - c.min()))
    settings = one_se_settings(cost, wslr)
    ms = [m for m, _ in settings]
    put("handover.cost.set_1se.m_min", min(ms), 0.0)
    put("handover.cost.set_1se.m_max", max(ms), 0.0)
    put("handover.cost.set_1se.n_settings", len(settings), 0.0)
    n_grid = sum(1 if int(m) == 1 else cost["alpha"].size for m in cost["m"].values)
    put("handover.cost.set_1se.n_grid", n_grid, 0.0)
    for m in cost["m"].values:
        name = f"handover.cost.min.m{int(m)}"
        if name in SPECS:
            put(name, float(cost["cost_min_m"].sel(wslr=wslr, m=m)), float(cost["cost_min_m_se"].sel(wslr=wslr, m=m)))
        name = f"handover.cost.full_grid_gain.m{int(m)}"
        if "full_grid_gain" in cost and name in SPECS and np.isfinite(float(cost["full_grid_gain"].sel(m=m))):
            put(name, float(cost["full_grid_gain"].sel(m=m)), float(cost["full_grid_gain_se"].sel(m=m)))
            put(f"handover.cost.full_grid_gain_se.m{int(m)}", float(cost["full_grid_gain_se"].sel(m=m)), 0.0)
    speeds = [float(s) for s in summary["speed_kmh"].values]
    for pol in POLICIES:
        for metric in ("success", "delay_ms", "delay_all_ms", "delay_trigger_ms", "pingpong", "rsrp_gap_db"):
            for v in (100.0, 250.0, 350.0):
                name = f"handover.{pol}.{metric}.v{v:g}"
                if name in SPECS and v in speeds:
                    put(name, _pick(summary, pol, metric, v), _pick(summary, pol, f"{metric}_se", v))
    _stage_keys(summary, speeds, out, put)
    hs = [s for s in speeds if 300 <= s <= 380]
    if hs:
        vals = [_pick(summary, "joint", "success", s) for s in hs]
        i = int(np.argmin(vals))
        put("handover.joint.success.min_v300_380", vals[i], _pick(summary, "joint", "success_se", hs[i]))
    lower = pingpong_strictly_lowest(summary)
    put("handover.claim.joint_pingpong_lowest_frac", float(np.mean(lower)))
    put("handover.claim.pingpong_tie_frac", float(np.mean(~lower)))
    gap = summary["rsrp_gap_db"].sel(policy=list(POLICIES)).values
    put("handover.claim.joint_gap_lowest_frac", float(np.mean(gap[0] < gap[1:].min(axis=0))))
    put("handover.gaph_db", gaph_db)
    put("handover.sigma0_db", sigma0_db)
    if radio is not None:
        lo, hi = gap_window_db(radio)
        put("handover.bound.first_attempt_success_xc", first_attempt_success_at_centre(radio), 0.0)
        put("handover.bound.gap_lo_db", lo, 0.0)
        put("handover.bound.gap_hi_db", hi, 0.0)
        put("handover.bound.gap_sigma_db", gap_sigma_db(radio), 0.0)
        put("handover.bound.t304_success_xc", t304_success_at_centre(radio), 0.0)
        put("handover.bound.t304_gap_hi_db", t304_gap_hi_db(radio), 0.0)
    put("handover.n_handovers_per_speed", float(summary["n_handovers"].min()))
    out.update(sens_values(sens))
    specs = sens_specs(sens)
    for name, spec in specs.items():
        _, _, var, pol, metric = name.split(".")
        val = float(sens[metric].sel(case=var, policy=pol))
        se = float(sens[f"{metric}_se"].sel(case=var, policy=pol))
        out[name] = spec.entry(val, se)
    for meth in cost["wslr"].values:
        name = f"handover.cost.best_m.{meth}"
        out[name] = KeySpec(name, "1", f"cost-minimizing m with the WSLR read as {meth}").entry(
            int(cost["best_m"].sel(wslr=meth)), 0.0
        )
    return out
