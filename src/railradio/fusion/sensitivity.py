"""Monte Carlo of the fusion sensitivity sweeps the source did not run (docs/model/fusion.md §5).

Two sweeps, each at the study's reference point (d, σ_TDOA, σ_AOA of ``fusion.reference``)
and with the main study's Monte Carlo engine (:mod:`railradio.fusion.montecarlo`): the
same train positions (:func:`~railradio.fusion.montecarlo.train_positions`), one generator
per position spawned from the point's key and the position index, chunked positions (the
shared loop :func:`~railradio.fusion.montecarlo.run_positions`):

* ``curve`` — the track a circular arc of radius R (:mod:`railradio.fusion.arc`; R = ∞, the
  source's straight track, is always the first point).  Estimators ``mismatch_*`` keep the
  straight line as the constraint, ``arc_*`` use the arc; ``*_tdoa``, ``*_aoa`` and
  ``*_fused`` (inverse-variance fusion with first-order variances propagated at the
  estimates, what a receiver can compute).  Errors are along the track (arc length).
* ``rho`` — two TDOAs with error correlation ρ (:mod:`railradio.fusion.correlated`):
  ``one_tdoa`` (the source's estimator: Δ2 and the AOA), ``naive`` (both TDOAs weighted as
  independent) and ``whitened`` (weighted with the correlation, BLUE).

Common random numbers: a point's randomness is keyed by its parameters *without* the swept
one, so every radius (every ρ) sees the same standard normal draws, and differences along a
sweep are not Monte Carlo noise.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import xarray as xr

from railradio.fusion.arc import (
    ArcGeometry,
    aoa_on_arc,
    aoa_variance_arc,
    fisher_information_arc,
    line_range_difference_slope,
    tdoa_on_arc,
    tdoa_on_line,
    tdoa_variance_arc,
)
from railradio.fusion.correlated import (
    correlated_pair,
    fisher_information_correlated,
    fuse_two_tdoa_aoa,
    range_difference0_m,
    range_difference0_slope,
    tdoa0_on_track,
)
from railradio.fusion.estimators import aoa_on_track, aoa_variance_propagated, clip_to_segment, fuse, tdoa_on_track
from railradio.fusion.geometry import CellGeometry
from railradio.fusion.montecarlo import PointParams, run_positions
from railradio.rng import spawn_key, stable_id

KINDS = ("curve", "rho")

ESTIMATORS = {
    "curve": ("mismatch_tdoa", "mismatch_aoa", "mismatch_fused", "arc_tdoa", "arc_aoa", "arc_fused"),
    "rho": ("one_tdoa", "naive", "whitened"),
}
ESTIMATOR_LABELS = {
    "mismatch_tdoa": "TDOA, straight-line constraint",
    "mismatch_aoa": "AOA, straight-line constraint",
    "mismatch_fused": "fusion, straight-line constraint (mismatch)",
    "arc_tdoa": "TDOA, arc constraint",
    "arc_aoa": "AOA, arc constraint",
    "arc_fused": "fusion, arc constraint",
    "one_tdoa": "fusion, one TDOA (the source's)",
    "naive": "fusion, two TDOAs weighted as independent",
    "whitened": "fusion, two TDOAs whitened (BLUE)",
}
SWEEP_COORD = {"curve": "curvature_per_m", "rho": "rho"}

_REFERENCE_KEYS = ("d_m", "sigma_tdoa_us", "sigma_aoa_rad")
_MC_KEYS = ("position_sampling", "cell_radius_factor", "clip")


# --- config -> points ------------------------------------------------------------------
def sens_points(study_cfg: dict, kind: str) -> list[dict]:
    """The plain-value parameters of every point of one sensitivity sweep.

    ``study_cfg`` is the config's ``fusion`` section; points take d, σ_TDOA, σ_AOA from its
    ``reference``, the Monte Carlo size from ``sensitivity`` and sampling/clip/cell radius
    from the study.  ``curve``: ``radius_m`` None (the straight base) then each of
    ``sensitivity.radii_m``; ``rho``: each of ``sensitivity.rho``.  Every point is
    validated here (a radius the layout cannot take raises ValueError naming it).

    Parameters
    ----------
    study_cfg : dict
        The config's ``fusion`` section: ``reference`` (``d_m`` [m], ``sigma_tdoa_us`` [µs],
        ``sigma_aoa_rad`` [rad]), ``position_sampling``, ``cell_radius_factor``, ``clip``, and
        ``sensitivity`` with ``n_positions``, ``n_trials``, ``radii_m`` [m] and ``rho`` [1].
    kind : {"curve", "rho"}
        The sweep.

    Returns
    -------
    list of dict
        One plain-value, key-sorted dict per point: ``d_m``, ``sigma_tdoa_us``,
        ``sigma_aoa_rad``, ``position_sampling``, ``cell_radius_factor``, ``clip``,
        ``n_positions``, ``n_trials``, ``kind`` and the swept ``radius_m`` [m] (None: the
        straight track) or ``rho`` [1]; the config's units (σ_TDOA in µs).

    Raises
    ------
    ValueError
        If ``kind`` is not ``"curve"`` or ``"rho"``, or a point is invalid (see
        :func:`point_params`).
    """
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    sens = study_cfg["sensitivity"]
    base = {k: study_cfg["reference"][k] for k in _REFERENCE_KEYS}
    base.update({k: study_cfg[k] for k in _MC_KEYS})
    base.update({"n_positions": sens["n_positions"], "n_trials": sens["n_trials"], "kind": kind})
    if kind == "curve":
        values = [None] + [float(r) for r in sens["radii_m"]]
        swept = "radius_m"
    else:
        values = [float(r) for r in sens["rho"]]
        swept = "rho"
    points = [dict(sorted({**base, swept: v}.items())) for v in values]
    for p in points:
        point_params(p)  # validate now (at DAG construction), not in a job
    return points


@dataclass(frozen=True)
class SensPoint:
    """One point of a sensitivity sweep: the main study's :class:`PointParams` plus the swept
    value (``radius_m``: math.inf for the straight track; ``rho``: TDOA error correlation).

    Parameters
    ----------
    base : PointParams
        The reference point and the Monte Carlo settings (SI units).
    kind : {"curve", "rho"}
        The sweep the point belongs to.
    radius_m : float, default math.inf
        Track radius of curvature R [m] (``curve``); math.inf is the straight track.
    rho : float, default 0.0
        Correlation coefficient of the two TDOA errors [1] (``rho``), in (-1, 1).

    Raises
    ------
    ValueError
        If ``kind`` is not one of ``"curve"``, ``"rho"``, ``rho`` is not in (-1, 1), or (for
        ``curve``) the layout cannot take ``radius_m`` (:class:`~railradio.fusion.arc.ArcGeometry`).
    """

    base: PointParams
    kind: str
    radius_m: float = math.inf
    rho: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}, got {self.kind!r}")
        if not (-1.0 < self.rho < 1.0):
            raise ValueError(f"rho must be in (-1, 1), got {self.rho!r}")
        if self.kind == "curve":
            self.arc  # noqa: B018 - validates radius_m against the layout

    @property
    def arc(self) -> ArcGeometry:
        """The point's :class:`~railradio.fusion.arc.ArcGeometry` (d, R, cell radius factor)."""
        return ArcGeometry(self.base.d_m, self.radius_m, self.base.cell_radius_factor)


def point_params(point: dict) -> SensPoint:
    """:class:`SensPoint` (SI units) of a point of :func:`sens_points`.

    Parameters
    ----------
    point : dict
        One point of :func:`sens_points` (config units: ``sigma_tdoa_us`` [µs]).

    Returns
    -------
    SensPoint
        ``base`` in SI units (``sigma_tdoa_s`` = ``sigma_tdoa_us`` · 1e-6 [s]); ``curve``:
        ``radius_m`` [m] (a None radius -> math.inf); ``rho``: ``rho`` [1].

    Raises
    ------
    ValueError
        If a value is out of the range :class:`PointParams`, :class:`SensPoint` or
        :class:`~railradio.fusion.arc.ArcGeometry` checks.
    """
    base = PointParams(
        d_m=float(point["d_m"]),
        sigma_tdoa_s=float(point["sigma_tdoa_us"]) * 1e-6,
        sigma_aoa_rad=float(point["sigma_aoa_rad"]),
        n_positions=int(point["n_positions"]),
        n_trials=int(point["n_trials"]),
        cell_radius_factor=float(point["cell_radius_factor"]),
        position_sampling=point["position_sampling"],
        clip=point["clip"],
    )
    if point["kind"] == "curve":
        r = point["radius_m"]
        return SensPoint(base, "curve", radius_m=math.inf if r is None else float(r))
    return SensPoint(base, "rho", rho=float(point["rho"]))


def point_key(point: dict) -> tuple[int, ...]:
    """Spawn key of a point: its parameters without the swept value (common random numbers
    along the sweep), tagged as a sensitivity point.

    Parameters
    ----------
    point : dict
        One point of :func:`sens_points`.

    Returns
    -------
    tuple of int
        ``spawn_key("fusion", stable_id({"sensitivity": point without radius_m and rho}))``:
        the same key for every point of one sweep.
    """
    unswept = {k: v for k, v in point.items() if k not in ("radius_m", "rho")}
    return spawn_key("fusion", stable_id({"sensitivity": unswept}))


# --- Monte Carlo ---------------------------------------------------------------------
def _clip(
    x: np.ndarray, no_solution: np.ndarray, segment_geom: CellGeometry, rule: str
) -> tuple[np.ndarray, np.ndarray]:
    """The main study's clip rule (``fusion.clip``): ``no_solution`` clips only the trials
    without solution (and non-finite estimates), ``segment`` every estimate off the segment."""
    x_clipped, off = clip_to_segment(x, segment_geom)
    if rule == "segment":
        return x_clipped, off
    mask = no_solution | ~np.isfinite(x)
    return np.where(mask, x_clipped, x), mask


def _curve_chunk(p: SensPoint, s_true: np.ndarray, z: np.ndarray) -> dict[str, np.ndarray]:
    """Estimates of one chunk of the curve sweep; s_true [P], z [2, P, T] ~ N(0, 1)."""
    b, arc, cell = p.base, p.arc, p.arc.cell
    s = s_true[:, None]
    delta_hat = arc.range_difference_m(s) + b.sigma_delta_m * z[0]
    theta_hat = arc.aoa_rad(s) + b.sigma_aoa_rad * z[1]
    bs2 = arc.bs_xy_m[1]
    out: dict[str, np.ndarray] = {}
    # the source's estimator: straight line y = 0, true BS coordinates (BS1 = (0, d))
    x_t, nosol_m = tdoa_on_line(delta_hat, b.d_m, bs2)
    x_t, clip_mt = _clip(x_t, nosol_m, cell, b.clip)
    x_a = aoa_on_track(theta_hat, cell)
    x_a, clip_ma = _clip(x_a, np.zeros_like(nosol_m), cell, b.clip)
    var_t = b.sigma_delta_m**2 / line_range_difference_slope(x_t, b.d_m, bs2) ** 2
    out["mismatch_tdoa"], out["mismatch_aoa"] = x_t, x_a
    out["mismatch_fused"] = fuse(x_t, var_t, x_a, aoa_variance_propagated(x_a, b.sigma_aoa_rad, cell))
    # the arc as the constraint
    s_t, nosol_a = tdoa_on_arc(delta_hat, arc)
    s_t, clip_at = _clip(s_t, nosol_a, cell, b.clip)
    s_a, clip_aa = _clip(aoa_on_arc(theta_hat, arc), np.zeros_like(nosol_a), cell, b.clip)
    out["arc_tdoa"], out["arc_aoa"] = s_t, s_a
    out["arc_fused"] = fuse(
        s_t, tdoa_variance_arc(s_t, b.sigma_delta_m, arc), s_a, aoa_variance_arc(s_a, b.sigma_aoa_rad, arc)
    )
    counts = {
        "n_mismatch_tdoa_no_solution": nosol_m,
        "n_mismatch_clipped": clip_mt | clip_ma,
        "n_arc_tdoa_no_solution": nosol_a,
        "n_arc_clipped": clip_at | clip_aa,
    }
    return {**out, **{k: v.sum(axis=1) for k, v in counts.items()}}


def _rho_chunk(p: SensPoint, x_true: np.ndarray, z: np.ndarray) -> dict[str, np.ndarray]:
    """Estimates of one chunk of the ρ sweep; x_true [P], z [3, P, T] ~ N(0, 1)."""
    b = p.base
    geom = b.geometry
    x = x_true[:, None]
    n2, n0 = correlated_pair(z[0], z[1], p.rho)
    delta2 = geom.range_difference_m(x) + b.sigma_delta_m * n2
    delta0 = range_difference0_m(x, geom) + b.sigma_delta_m * n0
    theta_hat = geom.aoa_rad(x) + b.sigma_aoa_rad * z[2]
    x_t2, nosol2 = tdoa_on_track(delta2, geom)
    x_t2, clip2 = _clip(x_t2, nosol2, geom, b.clip)
    x_t0, nosol0 = tdoa0_on_track(delta0, geom)
    x_t0, clip0 = _clip(x_t0, nosol0, geom, b.clip)
    x_a, clipa = _clip(aoa_on_track(theta_hat, geom), np.zeros_like(nosol2), geom, b.clip)
    sd2 = b.sigma_delta_m / geom.range_difference_slope(x_t2)  # signed: g2 < 0
    sd0 = b.sigma_delta_m / range_difference0_slope(x_t0, geom)  # signed: g0 > 0
    var_a = aoa_variance_propagated(x_a, b.sigma_aoa_rad, geom)
    out = {
        "one_tdoa": fuse(x_t2, sd2 * sd2, x_a, var_a),
        "naive": fuse_two_tdoa_aoa(x_t2, sd2, x_t0, sd0, x_a, var_a, 0.0),
        "whitened": fuse_two_tdoa_aoa(x_t2, sd2, x_t0, sd0, x_a, var_a, p.rho),
    }
    counts = {"n_tdoa_no_solution": nosol2 | nosol0, "n_clipped": clip2 | clip0 | clipa}
    return {**out, **{k: v.sum(axis=1) for k, v in counts.items()}}


_COUNT_LONG_NAMES = {
    "n_mismatch_tdoa_no_solution": "trials without TDOA solution on the straight line",
    "n_mismatch_clipped": "trials with a straight-line TDOA or AOA position clipped to the segment",
    "n_arc_tdoa_no_solution": "trials without TDOA solution on the arc's monotone branch",
    "n_arc_clipped": "trials with an arc TDOA or AOA position clipped to the segment",
    "n_tdoa_no_solution": "trials with either TDOA without solution",
    "n_clipped": "trials with any position clipped to the segment",
}


def simulate_sens_point(p: SensPoint, seed: int, key: tuple[int, ...], chunk_positions: int = 50) -> xr.Dataset:
    """Run one sensitivity point; per-position error statistics like
    :func:`railradio.fusion.simulate_point` (``mse``, ``bias``, ``sq_err_var`` over
    estimator × position, ``crlb_var``), errors along the track.

    Positions use ``key + (0,)``, the trials of position j ``key + (1, j)``: 2 (curve) or 3
    (ρ) rows of standard normals, the first two in the main study's order (range
    difference, angle; for ρ: Δ2, Δ0, angle).

    Parameters
    ----------
    p : SensPoint
        The sensitivity point.
    seed : int
        The config's master seed, >= 0.
    key : tuple of int
        The point's spawn key (:func:`point_key`).
    chunk_positions : int, default 50
        Positions processed at once (memory/speed only; results do not depend on it), >= 1.

    Returns
    -------
    xarray.Dataset
        Over (estimator, position), ``estimator`` = ``ESTIMATORS[p.kind]``: ``mse`` [m²],
        ``bias`` [m], ``sq_err_var`` [m⁴] (errors along the track); over (position):
        ``crlb_var`` [m²] (1/J of the arc or of the correlated-TDOA model) and the trial
        counts [1] (curve: ``n_mismatch_tdoa_no_solution``, ``n_mismatch_clipped``,
        ``n_arc_tdoa_no_solution``, ``n_arc_clipped``; ρ: ``n_tdoa_no_solution``,
        ``n_clipped``); coordinate ``x_true`` [m] (true train position along the track, arc
        length); scalars ``d_m`` [m], ``sigma_tdoa_s`` [s], ``sigma_delta_m`` [m],
        ``sigma_aoa_rad`` [rad], ``n_trials`` [1], ``radius_m`` [m], ``curvature_per_m`` [1/m],
        ``rho`` [1] and (curve) ``sagitta_m`` [m].

    Raises
    ------
    ValueError
        If ``chunk_positions`` < 1 or ``seed`` is not a non-negative integer.
    """
    estimators = ESTIMATORS[p.kind]
    n_rows = 2 if p.kind == "curve" else 3
    x_true, cat = run_positions(
        p.base, seed, key, n_rows, lambda xs, z: _sens_chunk_stats(p, estimators, xs, z), chunk_positions
    )
    return _sens_dataset(p, estimators, x_true, cat)


def _sens_chunk_stats(
    p: SensPoint, estimators: tuple[str, ...], xs: np.ndarray, z: np.ndarray
) -> dict[str, np.ndarray]:
    """Per-position statistics of one chunk: ``mse`` [m²], ``bias`` [m], ``sq_err_var`` [m⁴]
    over estimator × position and the trial counts per position; xs [P], z [n_rows, P, T]."""
    est = (_curve_chunk if p.kind == "curve" else _rho_chunk)(p, xs, z)
    stats: dict[str, np.ndarray] = {}
    err = np.stack([est[e] for e in estimators]) - xs[None, :, None]  # [E, P, T]
    sq = err * err
    stats["mse"] = sq.mean(axis=2)
    stats["bias"] = err.mean(axis=2)
    stats["sq_err_var"] = sq.var(axis=2, ddof=1)
    stats.update({k: v for k, v in est.items() if k.startswith("n_")})
    return stats


def _sens_dataset(
    p: SensPoint, estimators: tuple[str, ...], x_true: np.ndarray, cat: dict[str, np.ndarray]
) -> xr.Dataset:
    """The dataset of :func:`simulate_sens_point` from the true positions [m] and the
    per-position statistics; adds ``crlb_var`` [m²] (arc or correlated-TDOA bound)."""
    b = p.base
    if p.kind == "curve":
        arc = p.arc
        crlb_var = 1.0 / fisher_information_arc(x_true, b.sigma_delta_m, b.sigma_aoa_rad, arc)
        crlb_name = "Cramer-Rao bound on the along-track variance (arc model), 1/J(s)"
    else:
        crlb_var = 1.0 / fisher_information_correlated(x_true, b.sigma_delta_m, b.sigma_aoa_rad, p.rho, b.geometry)
        crlb_name = "Cramer-Rao bound on the position variance (two correlated TDOAs + AOA), 1/J(x)"
    pos = ("position",)
    ds = xr.Dataset(
        {
            "mse": (
                ("estimator", "position"),
                cat["mse"],
                {"units": "m2", "long_name": "mean squared along-track error over trials"},
            ),
            "bias": (
                ("estimator", "position"),
                cat["bias"],
                {"units": "m", "long_name": "mean along-track error over trials"},
            ),
            "sq_err_var": (
                ("estimator", "position"),
                cat["sq_err_var"],
                {"units": "m4", "long_name": "sample variance of the squared error over trials"},
            ),
            "crlb_var": (pos, crlb_var, {"units": "m2", "long_name": crlb_name}),
        },
        coords={
            "estimator": ("estimator", list(estimators), {"units": "1", "long_name": "position estimator"}),
            "x_true": (pos, x_true, {"units": "m", "long_name": "true train position along the track (arc length)"}),
        },
    )
    for name, long_name in _COUNT_LONG_NAMES.items():
        if name in cat:
            ds[name] = (pos, cat[name].astype(np.int64), {"units": "1", "long_name": long_name})
    arc = ArcGeometry(b.d_m, p.radius_m, b.cell_radius_factor) if p.kind == "curve" else None
    scalars = {
        "d_m": (b.d_m, "m", "base-station distance from the track"),
        "sigma_tdoa_s": (b.sigma_tdoa_s, "s", "TDOA error standard deviation (each TDOA)"),
        "sigma_delta_m": (b.sigma_delta_m, "m", "range-difference error standard deviation (each TDOA)"),
        "sigma_aoa_rad": (b.sigma_aoa_rad, "rad", "AOA error standard deviation"),
        "n_trials": (b.n_trials, "1", "trials per position"),
        "radius_m": (p.radius_m, "m", "track radius of curvature (inf: straight)"),
        "curvature_per_m": (0.0 if arc is None else arc.curvature_per_m, "1/m", "track curvature 1/R"),
        "rho": (p.rho, "1", "correlation coefficient of the two TDOA errors"),
    }
    if arc is not None:
        scalars["sagitta_m"] = (
            float(arc.sagitta_m(arc.half_segment_m)),
            "m",
            "offset of the arc from its tangent at the cell's far train position s = L",
        )
    for name, (val, units, long_name) in scalars.items():
        ds[name] = ((), val, {"units": units, "long_name": long_name})
    ds.attrs["sens_point_json"] = repr({"kind": p.kind, "radius_m": p.radius_m, "rho": p.rho, **asdict(p.base)})
    return ds


def summarize_sens(ds: xr.Dataset) -> dict[str, float]:
    """RMSE per estimator over trials and positions, its Monte Carlo standard error (as in
    :func:`railradio.fusion.summarize`), the RMS over positions of the per-position bias,
    the aggregated CRLB sqrt(mean 1/J) and the shares of the counted trials.

    Parameters
    ----------
    ds : xarray.Dataset
        A dataset of :func:`simulate_sens_point`.

    Returns
    -------
    dict of str to float
        For each estimator e of ``ds`` (``ESTIMATORS[kind]``): ``rmse_<e>_m`` [m], the
        along-track RMSE over trials and positions, ``rmse_<e>_se_m`` [m], its Monte Carlo
        standard error (0 where the RMSE is 0), and ``bias_rms_<e>_m`` [m], the RMS over
        positions of the per-position mean error; ``crlb_m`` [m]; and for each trial count
        ``n_<name>`` in ``ds``, ``frac_<name>`` [1], its share of all trials (curve:
        ``frac_mismatch_tdoa_no_solution``, ``frac_mismatch_clipped``,
        ``frac_arc_tdoa_no_solution``, ``frac_arc_clipped``; ρ: ``frac_tdoa_no_solution``,
        ``frac_clipped``).
    """
    n_pos = ds.sizes["position"]
    n_trials = int(ds["n_trials"])
    out: dict[str, float] = {}
    for est in ds["estimator"].values:
        mse = ds["mse"].sel(estimator=est)
        rmse = float(np.sqrt(mse.mean()))
        se_mse = float(np.sqrt((ds["sq_err_var"].sel(estimator=est) / n_trials).sum())) / n_pos
        out[f"rmse_{est}_m"] = rmse
        out[f"rmse_{est}_se_m"] = se_mse / (2.0 * rmse) if rmse > 0 else 0.0
        out[f"bias_rms_{est}_m"] = float(np.sqrt((ds["bias"].sel(estimator=est) ** 2).mean()))
    out["crlb_m"] = float(np.sqrt(ds["crlb_var"].mean()))
    for name in _COUNT_LONG_NAMES:
        if name in ds:
            out[name.replace("n_", "frac_", 1)] = float(ds[name].sum()) / (n_pos * n_trials)
    return out


def sens_sweep_dataset(points: list[xr.Dataset], kind: str) -> xr.Dataset:
    """Collect the points of one sensitivity sweep along ``curvature_per_m`` (curve) or
    ``rho``: ``rmse``, ``rmse_se``, ``bias_rms`` [estimator, point], ``crlb_m``, shares.

    Parameters
    ----------
    points : list of xarray.Dataset
        The datasets of :func:`simulate_sens_point` of one sweep, at least one, in any order.
    kind : {"curve", "rho"}
        The sweep.

    Returns
    -------
    xarray.Dataset
        Dimensions ``estimator`` × ``curvature_per_m`` [1/m] (curve) or ``rho`` [1], sorted
        along the latter: ``rmse``, ``rmse_se``, ``bias_rms`` [m] (along-track RMSE, its
        Monte Carlo standard error, RMS over positions of the bias) over both; ``crlb_m`` [m]
        and the shares ``frac_*`` [1] of the counted trials over the sweep; and along it
        ``d_m`` [m], ``sigma_delta_m`` [m], ``sigma_aoa_rad`` [rad] (curve also ``radius_m``
        and ``sagitta_m`` [m]).

    Raises
    ------
    ValueError
        If ``kind`` is not ``"curve"`` or ``"rho"``.
    """
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    coord = SWEEP_COORD[kind]
    estimators = list(ESTIMATORS[kind])
    summaries = [summarize_sens(p) for p in points]
    ds = xr.Dataset(
        coords={
            coord: (coord, [float(p[coord]) for p in points], dict(points[0][coord].attrs)),
            "estimator": ("estimator", estimators, {"units": "1", "long_name": "position estimator"}),
        }
    )
    for var, long_name in (
        ("rmse", "along-track RMSE over trials and positions"),
        ("rmse_se", "Monte Carlo standard error of the RMSE"),
        ("bias_rms", "RMS over positions of the mean error (bias)"),
    ):
        prefix = {"rmse": "rmse", "rmse_se": "rmse", "bias_rms": "bias_rms"}[var]
        suffix = "_se_m" if var == "rmse_se" else "_m"
        ds[var] = (
            ("estimator", coord),
            np.array([[s[f"{prefix}_{e}{suffix}"] for s in summaries] for e in estimators]),
            {"units": "m", "long_name": long_name},
        )
    ds["crlb_m"] = (
        (coord,),
        np.array([s["crlb_m"] for s in summaries]),
        {"units": "m", "long_name": "Cramer-Rao bound, sqrt(mean over positions of 1/J)"},
    )
    for name, long_name in _COUNT_LONG_NAMES.items():
        frac = name.replace("n_", "frac_", 1)
        if frac in summaries[0]:
            ds[frac] = (
                (coord,),
                np.array([s[frac] for s in summaries]),
                {"units": "1", "long_name": "share of " + long_name},
            )
    others = ("radius_m", "sagitta_m") if kind == "curve" else ()
    for other in others + ("d_m", "sigma_delta_m", "sigma_aoa_rad"):
        if other in points[0]:
            ds[other] = ((coord,), np.array([float(p[other]) for p in points]), dict(points[0][other].attrs))
    return ds.sortby(coord)
