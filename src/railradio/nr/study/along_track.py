"""Along-track and cross-track errors, the track-bound filter, and the along-track protection
level (docs/model/nr.md §6).

The 2-D EKF estimates the train's lateral position y although the train cannot leave its track;
the source fixes the track at y = 0. Here every tracker of the main run (both receivers, each
measurement set, with and without the χ² gate) runs twice on every realization: free in 2-D, as
the main run runs it, and **track-bound**
(:attr:`railradio.nr.tracking.ekf.TrackerConfig.track_bound`: y, v_y and a_y held at 0) with
the same calibrated W and q — the calibration's NEES does not identify q (§6, the q band), so
the track-bound filter keeps the 2-D filter's q and the comparison isolates what the track
constraint does [ours]. Errors are split along the track (x̂ − x) and across it (ŷ, the train
at y = 0); the IMM and the RTS-smoothed EKF of the ``nr_imm`` runs (their stored along-track
and 2-D errors) are split alike.

The along-track **protection level** at integrity risk P_IR is the filter's own bound PL = k
σ_x with σ_x = √P_xx and k = Φ⁻¹(1 − P_IR/2), the two-sided Gaussian quantile, for P_IR of
10⁻³, 10⁻⁴ and 10⁻⁵ [ours: a span, not one standard's value]. Whether it holds is measured: the
misleading-information (MI) rate is the share of scored epochs with |x̂ − x| > PL — a share per
epoch, not the per-hour or per-operation risk a specification states — with its 90 % two-sided
Clopper–Pearson interval [mi_lo, mi_hi]. The verdict, fixed before the run [ours]: the level
**holds** at P_IR when mi_hi < P_IR, **fails** when mi_lo > P_IR, and is **undecided**
otherwise (a run of n epochs can hold only when n ≥ 3/P_IR, the rule of three). Epochs are
correlated (the filter's memory), so the interval is narrower than the run's evidence: a
"holds" or "fails" is optimistic, an "undecided" is not. σ_x is computed at the calibrated q̂,
which the calibration does not identify (the q band), so PL and the MI rate are those of q̂.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr
from scipy.stats import beta, norm

from railradio.keynumbers import KeySpec
from railradio.nr.engine.simulate import Scenario
from railradio.nr.study.keys import SKIP_S
from railradio.nr.study.q_band import track_run
from railradio.nr.study.runs import tracker_name
from railradio.nr.tracking import loss
from railradio.nr.tracking.ekf import TrackerConfig, nees_position
from railradio.plotting import figure, save

RECEIVERS = ("robust", "source")
"""Receivers whose trackers are compared (our receiver, the source's)."""
MEASUREMENTS = ("aod", "toa", "aod_toa")
"""Measurement sets."""
GATES = (True, False)
"""With the χ² gate (the headline's setting) and without; the protection level's keys are the
gated headline tracker's."""
IMM_FILTERS = ("ekf", "imm", "rts")
"""The filters of the ``nr_imm`` runs (results/nr/imm/r*.nc): the gated AOD+TOA EKF, the IMM,
the RTS-smoothed EKF."""
MODELS = ("free", "track")
"""The 2-D EKF and the track-bound EKF."""
RISKS = (1e-3, 1e-4, 1e-5)
"""Integrity risks of the protection level [1]."""
LEVEL = 0.90
"""Two-sided level of the misleading-information rate's Clopper–Pearson interval [ours]."""
VERDICTS = {1: "holds", 0: "undecided", -1: "fails"}
"""The protection level's verdict codes (module docstring)."""
HEADLINE = ("robust", "aod_toa")
"""The headline tracker's receiver and measurement set."""
LABELS = {"free": "2-D EKF", "track": "track-bound EKF (y = 0)"}
"""Names of the models in keys and figures."""


def _risk_name(risk: float) -> str:
    return f"risk_e{round(-np.log10(risk))}"


def protection(e_along: np.ndarray, sigma: np.ndarray, risk: float) -> dict[str, float]:
    """The along-track protection level k σ_x at integrity risk ``risk`` and how often the error
    exceeded it (module docstring).

    Parameters
    ----------
    e_along : numpy.ndarray
        [n] along-track errors of the scored epochs [m] (NaN: no position, counted as an
        exceedance).
    sigma : numpy.ndarray
        [n] the filter's along-track standard deviation √P_xx [m] at those epochs.
    risk : float
        Integrity risk P_IR, in (0, 1).

    Returns
    -------
    dict
        ``pl_median_m``, ``pl_p95_m`` (the protection level over the epochs) [m], ``k`` [1],
        ``n`` and ``n_mi`` (epochs scored, exceedances), ``mi_rate`` [1], ``mi_lo`` and
        ``mi_hi`` (its Clopper–Pearson interval at :data:`LEVEL`) [1] and ``verdict`` (1 holds,
        0 undecided, -1 fails; :data:`VERDICTS`).

    Raises
    ------
    ValueError
        When ``risk`` is not in (0, 1) or the arrays differ in shape or are empty.
    """
    if not 0 < risk < 1:
        raise ValueError(f"risk must be in (0, 1), got {risk!r}")
    e, s = np.asarray(e_along, float), np.asarray(sigma, float)
    if e.shape != s.shape or e.size == 0:
        raise ValueError(f"e_along and sigma must be non-empty and of one shape, got {e.shape} and {s.shape}")
    k = float(norm.isf(risk / 2))
    pl = k * s
    exceeded = ~(np.abs(e) <= pl)  # NaN (no position) counts as misleading
    n, c = e.size, int(exceeded.sum())
    tail = (1 - LEVEL) / 2
    lo = float(beta.ppf(tail, c, n - c + 1)) if c > 0 else 0.0
    hi = float(beta.ppf(1 - tail, c + 1, n - c)) if c < n else 1.0
    finite = pl[np.isfinite(pl)]
    return {
        "pl_median_m": float(np.median(finite)) if finite.size else np.nan,
        "pl_p95_m": float(np.percentile(finite, 95)) if finite.size else np.nan,
        "k": k,
        "n": n,
        "n_mi": c,
        "mi_rate": c / n,
        "mi_lo": lo,
        "mi_hi": hi,
        "verdict": 1 if hi < risk else (-1 if lo > risk else 0),
    }


def _gate_name(gate: bool) -> str:
    return "" if gate else "ungated."


def _scored(runs, rx, scn, cfg, strength) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Along-track and cross-track errors, σ_x and the along-track NEES of one tracker over the
    realizations' scored epochs (t ≥ SKIP_S), pooled."""
    out = [[], [], [], []]
    for ds in runs:
        d = ds.sel(receiver=rx)
        o = track_run(d, scn, cfg, strength)
        keep = d["t"].values >= SKIP_S
        x_true = d["x_true"].values
        e_along = o["state"][:, 0] - x_true  # scoring: the truth is read here only
        nees = nees_position(o["state"], o["cov"], x_true, track_bound=True)  # e_x² / P_xx either way
        for lst, v in zip(out, (e_along, o["state"][:, 1], np.sqrt(o["cov"][:, 0, 0]), nees), strict=True):
            lst.append(v[keep])
    return tuple(np.concatenate(v) for v in out)


def _nan_stat(v: np.ndarray, fn) -> float:
    v = v[np.isfinite(v)]
    return float(fn(v)) if v.size else np.nan


STATS = ("along_mean_m", "along_p95_m", "cross_mean_m", "cross_p95_m", "err_mean_m", "lost_frac")
"""The accuracy of one tracker (:func:`_accuracy`)."""
PL_KEYS = ("pl_median_m", "pl_p95_m", "mi_rate", "mi_lo", "mi_hi", "n_mi", "n_scored", "verdict")
"""The protection level's variables, per risk."""
ATTRS = {
    "along_mean_m": ("m", "mean |along-track error| after SKIP_S"),
    "along_p95_m": ("m", "95th pct |along-track error| after SKIP_S"),
    "cross_mean_m": ("m", "mean |cross-track error| after SKIP_S (the train at y = 0)"),
    "cross_p95_m": ("m", "95th pct |cross-track error| after SKIP_S"),
    "err_mean_m": ("m", "mean 2-D error after SKIP_S"),
    "lost_frac": ("1", "share of scored epochs lost (2-D error above half the RRH spacing)"),
    "nees_median": ("1", "median along-track NEES e_x^2/P_xx (chi2_1 median 0.455)"),
    "q": ("m2 s-5", "white-jerk intensity (the 2-D filter's calibration)"),
    "pl_median_m": ("m", "median along-track protection level k sigma_x"),
    "pl_p95_m": ("m", "95th pct along-track protection level"),
    "mi_rate": ("1", "share of scored epochs with |along-track error| > protection level"),
    "mi_lo": ("1", f"{LEVEL:.0%} Clopper-Pearson interval of mi_rate: low"),
    "mi_hi": ("1", f"{LEVEL:.0%} Clopper-Pearson interval of mi_rate: high"),
    "n_mi": ("1", "epochs with |along-track error| > protection level"),
    "n_scored": ("1", "epochs scored"),
    "verdict": ("1", "protection level: 1 holds (mi_hi < risk), -1 fails (mi_lo > risk), 0 undecided"),
}
"""Units and descriptions of the dataset's variables (the IMM's carry an ``imm_`` prefix)."""


def _accuracy(e_along: np.ndarray, e_cross: np.ndarray, spacing_m: float) -> dict[str, float]:
    """:data:`STATS` of pooled along- and cross-track errors [m] (NaN: no position)."""
    err = np.hypot(e_along, e_cross)
    a, c = np.abs(e_along), np.abs(e_cross)
    return {
        "along_mean_m": _nan_stat(a, np.mean),
        "along_p95_m": _nan_stat(a, lambda v: np.percentile(v, 95)),
        "cross_mean_m": _nan_stat(c, np.mean),
        "cross_p95_m": _nan_stat(c, lambda v: np.percentile(v, 95)),
        "err_mean_m": _nan_stat(err, np.mean),
        "lost_frac": float(np.mean(loss.lost_mask(err, spacing_m))),
    }


def imm_along(imm_runs: Sequence[xr.Dataset], spacing_m: float) -> dict[str, np.ndarray]:
    """The ``nr_imm`` filters' errors along and across the track, pooled over the
    realizations' scored epochs (t ≥ SKIP_S): the along-track error is stored, the
    cross-track one is the rest of the 2-D error, √(e² − e_x²) = |ŷ|.

    Parameters
    ----------
    imm_runs : sequence of xarray.Dataset
        The realizations' ``results/nr/imm/r*.nc`` (``along_err``, ``pos_err`` [m] per
        (``filter``, ``epoch``), ``t`` [s]).
    spacing_m : float
        RRH spacing [m] (the loss rule).

    Returns
    -------
    dict of str to numpy.ndarray
        :data:`STATS` over :data:`IMM_FILTERS`.
    """
    out = {k: np.full(len(IMM_FILTERS), np.nan) for k in STATS}
    for i, f in enumerate(IMM_FILTERS):
        along, cross = [], []
        for ds in imm_runs:
            keep = ds["t"].values >= SKIP_S
            a, e = (ds[v].sel(filter=f).values[keep] for v in ("along_err", "pos_err"))
            along.append(a)
            cross.append(np.sqrt(np.maximum(e**2 - a**2, 0.0)))
        for k, v in _accuracy(np.concatenate(along), np.concatenate(cross), spacing_m).items():
            out[k][i] = v
    return out


def along_track(
    runs: Sequence[xr.Dataset],
    scn: Scenario,
    cal: dict[str, dict],
    tracker: dict[str, Any],
    selection: dict[str, str],
    spacing_m: float,
    imm_runs: Sequence[xr.Dataset] = (),
) -> xr.Dataset:
    """Every tracker free and track-bound on every realization: errors along and across the
    track, the loss share, the along-track NEES and the protection level; the ``nr_imm``
    filters' errors split alike.

    Parameters
    ----------
    runs : sequence of xarray.Dataset
        Each evaluation realization's estimates, all receivers
        (:func:`railradio.nr.study.runs.read_shards` and :func:`~railradio.nr.study.runs.point_model`).
    scn : Scenario
        The scenario (deployment, ``trajectory.dt_s``).
    cal : dict of str to dict
        The calibration records (``results/nr/calibration.json``).
    tracker : dict
        The ``nr.tracker`` config section (``gate_prob``).
    selection : dict of str to str
        Receiver name -> strength measure of its measured RRHs.
    spacing_m : float
        RRH spacing [m], the loss rule's threshold (:func:`railradio.nr.tracking.loss.lost_mask`).
    imm_runs : sequence of xarray.Dataset
        The realizations' IMM runs (:func:`imm_along`); none: no ``imm_*`` variables.

    Returns
    -------
    xarray.Dataset
        Over (``receiver``, ``measurements``, ``gate``, ``model``): ``along_mean_m``,
        ``along_p95_m`` (|x̂ − x|), ``cross_mean_m``, ``cross_p95_m`` (|ŷ|), ``err_mean_m``
        (2-D) [m], ``lost_frac`` [1], ``nees_median`` (along-track, against χ²₁'s median 0.455)
        [1], ``q`` [m² s⁻⁵]; and over ``risk`` too: ``pl_median_m``, ``pl_p95_m`` [m],
        ``mi_rate``, ``mi_lo``, ``mi_hi`` [1], ``n_mi``, ``n_scored``, ``verdict`` (1 holds,
        0 undecided, -1 fails); over ``filter`` (:data:`IMM_FILTERS`): ``imm_`` + each of
        :data:`STATS`.

    Raises
    ------
    KeyError
        When the calibration lacks a tracker of :data:`RECEIVERS` × :data:`MEASUREMENTS` ×
        :data:`GATES`.
    """
    shape = (len(RECEIVERS), len(MEASUREMENTS), len(GATES), len(MODELS))
    stats = {k: np.full(shape, np.nan) for k in (*STATS, "nees_median", "q")}
    pls = {k: np.full(shape + (len(RISKS),), np.nan) for k in PL_KEYS}
    for at in np.ndindex(shape):
        rx, meas, gate, model = RECEIVERS[at[0]], MEASUREMENTS[at[1]], GATES[at[2]], MODELS[at[3]]
        cfg = TrackerConfig.from_record(
            cal[tracker_name(rx, meas, gate)],
            measurements=meas,
            gate=gate,
            gate_prob=tracker["gate_prob"],
            track_bound=model == "track",
        )
        e_a, e_c, sig, nees = _scored(runs, rx, scn, cfg, selection[rx])
        for k, v in _accuracy(e_a, e_c, spacing_m).items():
            stats[k][at] = v
        stats["nees_median"][at] = _nan_stat(nees, np.median)
        stats["q"][at] = cfg.q
        for r, risk in enumerate(RISKS):
            p = protection(e_a, sig, risk)
            for k, src in zip(PL_KEYS, (*PL_KEYS[:-2], "n", "verdict"), strict=True):
                pls[k][at + (r,)] = float(p[src])
    dims = ("receiver", "measurements", "gate", "model")
    data = {k: (dims, v, {"units": ATTRS[k][0], "long_name": ATTRS[k][1]}) for k, v in stats.items()}
    data |= {k: (dims + ("risk",), v, {"units": ATTRS[k][0], "long_name": ATTRS[k][1]}) for k, v in pls.items()}
    if imm_runs:
        imm = imm_along(imm_runs, spacing_m)
        data |= {f"imm_{k}": (("filter",), v, {"units": ATTRS[k][0], "long_name": ATTRS[k][1]}) for k, v in imm.items()}
    coords = {
        "receiver": ("receiver", list(RECEIVERS), {"units": "1", "long_name": "receiver"}),
        "measurements": ("measurements", list(MEASUREMENTS), {"units": "1", "long_name": "measurement set"}),
        "gate": ("gate", [int(g) for g in GATES], {"units": "1", "long_name": "chi-square gate (1 on, 0 off)"}),
        "model": ("model", list(MODELS), {"units": "1", "long_name": "free: 2-D EKF; track: track-bound EKF (y = 0)"}),
        "risk": ("risk", list(RISKS), {"units": "1", "long_name": "integrity risk"}),
    }
    if imm_runs:
        coords["filter"] = ("filter", list(IMM_FILTERS), {"units": "1", "long_name": "nr_imm filter"})
    return xr.Dataset(data, coords=coords, attrs={"skip_s": SKIP_S, "level": LEVEL})


def key_numbers(at: xr.Dataset) -> dict[str, Any]:
    """Key numbers ``nr.along.*`` of :func:`along_track`'s dataset: every tracker's along-track
    mean and 95th percentile, the free filter's cross-track mean and the loss share (an
    accuracy is null when lost, :func:`railradio.nr.tracking.loss.accuracy`; the ungated
    trackers' under ``<receiver>.<measurements>.ungated.``), the same of the IMM filters
    (``nr.along.imm.<filter>.``) when the dataset has them, and the gated headline tracker's
    protection level at each risk, free and track-bound: its median, the MI rate, its interval
    and the verdict (null with the track lost).

    Parameters
    ----------
    at : xarray.Dataset
        :func:`along_track`'s output.

    Returns
    -------
    dict
        Key-number entries (:meth:`railradio.keynumbers.KeySpec.entry`).
    """
    out: dict[str, Any] = {}

    def put(name, unit, desc, value, lost_frac=None, digits=3):
        v = None if value is None or not np.isfinite(value) else float(value)
        if lost_frac is not None:
            v = loss.accuracy(v, lost_frac)
        out[f"nr.along.{name}"] = KeySpec(f"nr.along.{name}", unit, desc, digits=digits).entry(v, lost_frac=lost_frac)

    def accuracy(base, s, what, cross=True):
        lost = float(s["lost_frac"])
        rows = [("along_m.mean", "along_mean_m", "mean |along-track error|")]
        rows += [("along_m.p95", "along_p95_m", "95th pct |along-track error|")]
        if cross:
            rows += [("cross_m.mean", "cross_mean_m", "mean |cross-track error|")]
        for name, var, desc in rows:
            put(f"{base}.{name}", "m", f"{desc} of the {what}", float(s[var]), lost)
        put(f"{base}.lost_frac", "1", f"share of epochs lost by the {what}", lost)

    for rx, meas, gate, model in itertools.product(RECEIVERS, MEASUREMENTS, GATES, MODELS):
        s = at.sel(receiver=rx, measurements=meas, gate=int(gate), model=model)
        what = f"{LABELS[model]}, {rx} receiver, {meas}, {'chi2 gate' if gate else 'no gate'}"
        # the track-bound filter's ŷ is 0 by construction: no cross-track key
        accuracy(f"{rx}.{meas}.{_gate_name(gate)}{model}", s, what, cross=model == "free")
    if "filter" in at.dims:
        names = {"ekf": "gated AOD+TOA EKF", "imm": "IMM", "rts": "RTS-smoothed EKF"}
        for f in IMM_FILTERS:
            s = at[[f"imm_{k}" for k in STATS]].sel(filter=f).rename({f"imm_{k}": k for k in STATS})
            accuracy(f"imm.{f}", s, f"{names[f]} of the IMM runs (nr_imm)")
    rx, meas = HEADLINE
    head = at.sel(receiver=rx, measurements=meas, gate=1)
    put(f"{rx}.{meas}.n_scored", "1", "epochs scored per tracker", float(head["n_scored"].max()), digits=5)
    for model in MODELS:
        lost = float(head["lost_frac"].sel(model=model))
        for risk in RISKS:
            s = head.sel(model=model, risk=risk)
            what = f"the {LABELS[model]} of the headline tracker at integrity risk {risk:.0e}"
            base = f"{rx}.{meas}.{model}.{_risk_name(risk)}"
            rows = [("pl_m.median", "m", "median along-track protection level k sigma_x of", "pl_median_m", 3)]
            rows += [("mi_rate", "1", "share of epochs whose along-track error exceeds the level,", "mi_rate", 2)]
            rows += [("mi_lo", "1", f"{LEVEL:.0%} Clopper-Pearson interval of that share, low,", "mi_lo", 2)]
            rows += [("mi_hi", "1", f"{LEVEL:.0%} Clopper-Pearson interval of that share, high,", "mi_hi", 2)]
            rows += [("verdict", "1", "protection level 1 holds, 0 undecided, -1 fails:", "verdict", 1)]
            for name, unit, desc, var, digits in rows:
                put(f"{base}.{name}", unit, f"{desc} {what}", float(s[var]), lost, digits=digits)
    return out


def plot_along(at: xr.Dataset, pdf, png) -> None:
    """Figure ``nr_along_track``: our receiver's gated trackers, free and track-bound, their
    mean error along and across the track (left; a lost tracker marked), and the headline
    tracker's misleading-information rate against the integrity risk its protection level is
    set for, with its Clopper–Pearson interval (right; the level holds where the whole
    interval lies below the diagonal, fails where it lies above, and a run with no exceedance
    is drawn as an arrow at the bottom).

    Parameters
    ----------
    at : xarray.Dataset
        :func:`along_track`'s output.
    pdf, png : str or os.PathLike
        Output paths.

    Returns
    -------
    None
        The figure is written to ``pdf`` and ``png``.
    """
    fig, (ab, ap) = figure(ncols=2, figsize=(10.0, 4.0), layout="constrained")
    at = at.sel(gate=1)  # the gated trackers
    rx = HEADLINE[0]
    width = 0.25
    xs = np.arange(len(MEASUREMENTS))
    bars = (("free", "along_mean_m", "2-D EKF, along"), ("free", "cross_mean_m", "2-D EKF, across"))
    bars += (("track", "along_mean_m", "track-bound EKF, along"),)
    for b, (model, var, name) in enumerate(bars):
        s = at.sel(receiver=rx, model=model)
        lost = s["lost_frac"].values >= loss.LOST_FRAC_MAX  # the keys' rule (loss.accuracy)
        ab.plot(xs + (b - 1) * width, np.where(lost, np.nan, s[var].values), "os^"[b], ms=7, label=name)
    for x, meas in zip(xs, MEASUREMENTS, strict=True):
        lost = at["lost_frac"].sel(receiver=rx, measurements=meas).values >= loss.LOST_FRAC_MAX
        if lost.any():
            which = "both lost" if lost.all() else LABELS[MODELS[int(np.argmax(lost))]].split(" (")[0] + " lost"
            ab.text(x, 0.05, which, ha="center", fontsize=7, transform=ab.get_xaxis_transform())
    ab.set_xlim(-0.5, len(MEASUREMENTS) - 0.5)
    ab.set_xticks(xs, [m.replace("_", "+").upper() for m in MEASUREMENTS])
    ab.set_yscale("log")
    ab.set_ylim(1e-2, 1e2)
    ab.set_ylabel(f"mean |error| after {at.attrs['skip_s']:g} s [m]")
    ab.set_title("our receiver, gated trackers", fontsize=9)
    ab.legend(fontsize=7)
    risks = at["risk"].values
    floor = 1e-6
    for model, mk, shift in (("free", "o", 0.85), ("track", "s", 1.15)):
        s = at.sel(receiver=rx, measurements=HEADLINE[1], model=model)
        rate, lo, hi = (s[v].values for v in ("mi_rate", "mi_lo", "mi_hi"))
        x = risks * shift  # side by side at each risk
        line = ap.errorbar(
            x, np.where(rate > 0, rate, np.nan), yerr=[rate - lo, hi - rate], fmt=mk, capsize=3, label=LABELS[model]
        )
        zero = rate == 0
        ap.vlines(x[zero], floor, hi[zero], color=line[0].get_color())
        ap.plot(x[zero], np.full(zero.sum(), floor), "v", color=line[0].get_color(), ms=7)
    ap.plot([1e-6, 1e-2], [1e-6, 1e-2], "k:", lw=0.8)
    ap.set_xscale("log")
    ap.set_yscale("log")
    ap.set_ylim(floor / 2, 1e-2)
    ap.set_xlabel("integrity risk the protection level is set for")
    ap.set_ylabel("MI rate: share of epochs with |along-track error| > PL")
    ap.set_title(f"headline tracker; bars {at.attrs['level']:.0%} Clopper-Pearson; ▼: no exceedance", fontsize=9)
    ap.legend(fontsize=7)
    save(fig, pdf, png)
