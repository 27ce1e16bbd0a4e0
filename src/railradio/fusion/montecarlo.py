"""Monte Carlo driver of the fusion study, vectorized over positions × trials.

One call of :func:`simulate_point` is one sweep point (one d, σ_TDOA, σ_AOA): n_positions
train positions on [0, sqrt(R² - d²)], n_trials independent (TDOA, AOA) measurement pairs
at each (source §3.1: 1000 × 10 000).  Reading of the source [ours, stated in the paper]: the
source "takes the mean of several position measurements" per algorithm; we read it as
per-trial estimates whose mean and variance per position feed the fusion weights, and
the RMSE (eq. 11) over all trials and positions.

Every position draws its noise from its own generator, spawned from the point's key and
the position index, so results do not depend on how positions are chunked.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np
import xarray as xr

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.fusion.crlb import fisher_information
from railradio.fusion.estimators import (
    aoa_on_track,
    aoa_variance_propagated,
    clip_to_segment,
    fuse,
    tdoa_on_track,
    tdoa_variance_propagated,
)
from railradio.fusion.geometry import CellGeometry
from railradio.rng import make_rng

ESTIMATORS = ("tdoa", "aoa", "fused_genie", "fused_propagated")
"""Estimators compared: TDOA ∩ track, AOA ∩ track, and the inverse-variance fusion with
per-position Monte Carlo variances (``fused_genie``: the source's reading, which needs the
true position) or first-order variances propagated at the estimates (``fused_propagated``:
what a receiver can do)."""

ESTIMATOR_LABELS = {
    "tdoa": "TDOA",
    "aoa": "AOA",
    "fused_genie": "fusion (MC variances)",
    "fused_propagated": "fusion (propagated variances)",
}

SWEEP_PARAMETER = {"reference": "d_m", "d_m": "d_m", "sigma_tdoa_us": "sigma_tdoa_s", "sigma_aoa_rad": "sigma_aoa_rad"}
"""Config sweep name -> the SI coordinate of the sweep dataset."""


@dataclass(frozen=True)
class PointParams:
    """One sweep point.

    Parameters
    ----------
    d_m : float
        Base-station distance from the track [m], > 0 (checked when :attr:`geometry` is built).
    sigma_tdoa_s : float
        Standard deviation of the TDOA t_{2,1} [s] (source eq. 2; 0.1 µs ↔ 29.98 m), finite, > 0.
    sigma_aoa_rad : float
        Standard deviation of the AOA at the serving BS [rad], finite, > 0.
    n_positions, n_trials : int
        Train positions (>= 1) and trials per position (>= 2) [1].
    cell_radius_factor : float, default 2.0
        R / d (source: 2) [1], > 1 (checked when :attr:`geometry` is built).
    position_sampling : {"grid", "random"}, default "grid"
        ``"grid"``: midpoints of n_positions equal cells of [0, sqrt(R² - d²)]
        (stratified, lower Monte Carlo error); ``"random"``: uniform draws.
    clip : {"no_solution", "segment"}, default "no_solution"
        Which estimates are projected onto the serving cell's segment [-sqrt(R² - d²),
        sqrt(R² - d²)]: ``"no_solution"`` only those without a solution (a TDOA with
        |Δ| >= D, a non-finite AOA position); ``"segment"`` every estimate off the segment.

    Raises
    ------
    ValueError
        If a σ is not a finite number > 0, ``n_positions`` < 1, ``n_trials`` < 2, or
        ``position_sampling`` or ``clip`` is not one of its allowed values.
    """

    d_m: float
    sigma_tdoa_s: float
    sigma_aoa_rad: float
    n_positions: int
    n_trials: int
    cell_radius_factor: float = 2.0
    position_sampling: str = "grid"
    clip: str = "no_solution"

    def __post_init__(self) -> None:
        for name in ("sigma_tdoa_s", "sigma_aoa_rad"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a finite number > 0, got {v!r}")
        if self.n_positions < 1:
            raise ValueError(f"n_positions must be >= 1, got {self.n_positions!r}")
        if self.n_trials < 2:
            raise ValueError(f"n_trials must be >= 2, got {self.n_trials!r}")
        if self.position_sampling not in ("grid", "random"):
            raise ValueError(f"position_sampling must be 'grid' or 'random', got {self.position_sampling!r}")
        if self.clip not in ("no_solution", "segment"):
            raise ValueError(f"clip must be 'no_solution' or 'segment', got {self.clip!r}")

    @property
    def geometry(self) -> CellGeometry:
        """The point's :class:`CellGeometry` (``d_m``, ``cell_radius_factor``)."""
        return CellGeometry(self.d_m, self.cell_radius_factor)

    @property
    def sigma_delta_m(self) -> float:
        """Range-difference standard deviation c·σ_TDOA [m]."""
        return SPEED_OF_LIGHT_M_S * self.sigma_tdoa_s


POINT_KEYS = ("n_positions", "n_trials", "position_sampling", "cell_radius_factor", "clip")


def sweep_points(study_cfg: dict, sweep: str) -> list[dict]:
    """The plain-value parameters of every point of one sweep of the study's config.

    ``sweep`` is ``"reference"`` (one point) or a key of ``study_cfg["sweeps"]``; each
    point is the reference with the swept value replaced, plus the Monte Carlo settings,
    key-sorted (what Snakemake fingerprints and what seeds the point).

    Parameters
    ----------
    study_cfg : dict
        The config's ``fusion`` section: ``reference`` (``d_m`` [m], ``sigma_tdoa_us`` [µs],
        ``sigma_aoa_rad`` [rad]), ``sweeps`` (config sweep name -> list of values, in the
        reference's units) and the Monte Carlo settings ``n_positions``, ``n_trials``,
        ``position_sampling``, ``cell_radius_factor``, ``clip``.
    sweep : str
        ``"reference"`` or a key of ``study_cfg["sweeps"]`` (``"d_m"``, ``"sigma_tdoa_us"``,
        ``"sigma_aoa_rad"``).

    Returns
    -------
    list of dict
        One plain-value dict per point, in the order of the sweep's values (one for
        ``"reference"``), with the keys of ``reference`` and the Monte Carlo settings; the
        config's units (σ_TDOA in µs).  :func:`point_params` converts one to SI.

    Raises
    ------
    ValueError
        If ``sweep`` is neither ``"reference"`` nor a key of ``study_cfg["sweeps"]``.
    """
    if sweep != "reference" and sweep not in study_cfg["sweeps"]:
        raise ValueError(f"sweep must be 'reference' or one of {sorted(study_cfg['sweeps'])}, got {sweep!r}")
    values = [None] if sweep == "reference" else study_cfg["sweeps"][sweep]
    points = []
    for v in values:
        point = dict(study_cfg["reference"])
        if sweep != "reference":
            point[sweep] = v
        point.update({k: study_cfg[k] for k in POINT_KEYS})
        points.append(dict(sorted(point.items())))
    return points


def point_params(point: dict) -> PointParams:
    """:class:`PointParams` (SI units) of a point of :func:`sweep_points`.

    Parameters
    ----------
    point : dict
        One point of :func:`sweep_points`: ``d_m`` [m], ``sigma_tdoa_us`` [µs],
        ``sigma_aoa_rad`` [rad], ``n_positions``, ``n_trials``, ``cell_radius_factor``,
        ``position_sampling``, ``clip``.

    Returns
    -------
    PointParams
        The point in SI units (``sigma_tdoa_s`` = ``sigma_tdoa_us`` · 1e-6 [s]).

    Raises
    ------
    ValueError
        If a value is out of the range :class:`PointParams` checks.
    """
    return PointParams(
        d_m=float(point["d_m"]),
        sigma_tdoa_s=float(point["sigma_tdoa_us"]) * 1e-6,
        sigma_aoa_rad=float(point["sigma_aoa_rad"]),
        n_positions=int(point["n_positions"]),
        n_trials=int(point["n_trials"]),
        cell_radius_factor=float(point["cell_radius_factor"]),
        position_sampling=point["position_sampling"],
        clip=point["clip"],
    )


def train_positions(params: PointParams, rng: np.random.Generator) -> np.ndarray:
    """Train positions on [0, sqrt(R² - d²)] [m], shape [n_positions].

    Parameters
    ----------
    params : PointParams
        The sweep point: ``n_positions``, ``position_sampling`` and the geometry (``d_m``,
        ``cell_radius_factor``).
    rng : numpy.random.Generator
        Generator of the positions; drawn from only with ``position_sampling="random"``.

    Returns
    -------
    numpy.ndarray of float
        Train positions along the track [m], shape [n_positions], ascending: the midpoints of
        n_positions equal cells of the interval (``"grid"``) or sorted uniform draws on it
        (``"random"``).

    Raises
    ------
    ValueError
        If ``params.d_m`` or ``params.cell_radius_factor`` is out of range (:class:`CellGeometry`).
    """
    lo, hi = params.geometry.train_interval_m
    n = params.n_positions
    if params.position_sampling == "grid":
        return lo + (hi - lo) * (np.arange(n) + 0.5) / n
    return np.sort(rng.uniform(lo, hi, size=n))


def _chunk_stats(
    params: PointParams, x_true: np.ndarray, n_delta: np.ndarray, n_theta: np.ndarray
) -> dict[str, np.ndarray]:
    """Per-position statistics of one chunk. x_true [P]; n_delta, n_theta [P, T] ~ N(0, 1)."""
    geom = params.geometry
    x = x_true[:, None]  # [P, 1]
    delta_hat = geom.range_difference_m(x) + params.sigma_delta_m * n_delta  # [P, T]
    x_t, no_sol = tdoa_on_track(delta_hat, geom)
    theta_hat = geom.aoa_rad(x) + params.sigma_aoa_rad * n_theta  # [P, T]
    x_a = aoa_on_track(theta_hat, geom)
    x_t_clipped, clip_t = clip_to_segment(x_t, geom)
    x_a_clipped, clip_a = clip_to_segment(x_a, geom)
    if params.clip == "segment":
        x_t, x_a = x_t_clipped, x_a_clipped
    else:  # only estimates without solution (±inf) are clipped
        clip_t, clip_a = no_sol, ~np.isfinite(x_a)
        x_t = np.where(clip_t, x_t_clipped, x_t)
        x_a = np.where(clip_a, x_a_clipped, x_a)

    tiny = 1e-12  # [m²] guards a zero sample variance (every trial clipped to one end)
    var_t = np.maximum(x_t.var(axis=1, ddof=1), tiny)[:, None]
    var_a = np.maximum(x_a.var(axis=1, ddof=1), tiny)[:, None]
    x_fg = fuse(x_t, var_t, x_a, var_a)
    x_fp = fuse(
        x_t,
        tdoa_variance_propagated(x_t, params.sigma_delta_m, geom),
        x_a,
        aoa_variance_propagated(x_a, params.sigma_aoa_rad, geom),
    )

    out: dict[str, list[np.ndarray]] = {"mse": [], "bias": [], "sq_err_var": []}
    for est in (x_t, x_a, x_fg, x_fp):
        err = est - x
        sq = err * err
        out["mse"].append(sq.mean(axis=1))
        out["bias"].append(err.mean(axis=1))
        out["sq_err_var"].append(sq.var(axis=1, ddof=1))
    stats = {k: np.stack(v) for k, v in out.items()}  # [estimator, P]
    stats["n_tdoa_no_solution"] = no_sol.sum(axis=1)
    stats["n_tdoa_clipped"] = clip_t.sum(axis=1)
    stats["n_aoa_clipped"] = clip_a.sum(axis=1)
    return stats


def trial_normals(seed: int, key: tuple[int, ...], positions: range, n_rows: int, n_trials: int) -> np.ndarray:
    """Standard normals of the trials at ``positions``: [n_rows, len(positions), n_trials];
    position j draws its rows in order from its own generator ``key + (1, j)``, so a
    position's draws do not depend on the chunk it falls in.

    Parameters
    ----------
    seed : int
        The config's master seed, >= 0.
    key : tuple of int
        The point's spawn key; position j draws from ``key + (1, j)``.
    positions : range
        Indices j of the positions of the chunk.
    n_rows : int
        Rows of normals per position, one per noise source (2 in the main study: range
        difference and angle).
    n_trials : int
        Trials per position T.

    Returns
    -------
    numpy.ndarray of float
        Standard normal draws [1], shape [n_rows, len(positions), n_trials].

    Raises
    ------
    ValueError
        If ``seed`` is not a non-negative integer (:func:`railradio.rng.make_rng`).
    """
    z = np.empty((n_rows, len(positions), n_trials))
    for row, j in enumerate(positions):
        rng = make_rng(seed, key + (1, j))
        for r in range(n_rows):
            z[r, row] = rng.standard_normal(n_trials)
    return z


def run_positions(
    params: PointParams,
    seed: int,
    key: tuple[int, ...],
    n_rows: int,
    chunk_stats: Callable[[np.ndarray, np.ndarray], dict[str, np.ndarray]],
    chunk_positions: int = 50,
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The Monte Carlo loop of one sweep point, shared by the main study and the sensitivity
    sweeps: train positions from ``key + (0,)``, then chunks of positions, each with its
    ``n_rows`` rows of standard normals (:func:`trial_normals`).

    ``chunk_stats(x_true, z)`` maps a chunk's true positions [P] and normals [n_rows, P, T]
    to per-position statistics (last axis P).  Returns the true positions [n_positions] and
    the statistics concatenated over the chunks along their last axis.

    Parameters
    ----------
    params : PointParams
        The sweep point (``n_positions``, ``n_trials``, ``position_sampling``, geometry).
    seed : int
        The config's master seed, >= 0.
    key : tuple of int
        The point's spawn key; positions use ``key + (0,)``, the trials of position j
        ``key + (1, j)``.
    n_rows : int
        Rows of standard normals per position, one per noise source (2 in the main study:
        range difference and angle).
    chunk_stats : callable
        ``chunk_stats(x_true, z) -> dict of str to numpy.ndarray``: from the chunk's true
        positions [m], shape [P], and standard normals z, shape [n_rows, P, n_trials], the
        per-position statistics, each with last axis P.
    chunk_positions : int, default 50
        Positions processed at once (memory/speed only; results do not depend on it), >= 1.

    Returns
    -------
    x_true : numpy.ndarray of float
        True train positions along the track [m], shape [n_positions].
    stats : dict of str to numpy.ndarray
        The statistics of ``chunk_stats``, concatenated over the chunks along their last
        axis (length n_positions).

    Raises
    ------
    ValueError
        If ``chunk_positions`` < 1, ``seed`` is not a non-negative integer, or the geometry
        of ``params`` is out of range (:class:`CellGeometry`).
    """
    if chunk_positions < 1:
        raise ValueError(f"chunk_positions must be >= 1, got {chunk_positions!r}")
    x_true = train_positions(params, make_rng(seed, key + (0,)))
    n, t = params.n_positions, params.n_trials
    parts: list[dict[str, np.ndarray]] = []
    for start in range(0, n, chunk_positions):
        idx = range(start, min(start + chunk_positions, n))
        z = trial_normals(seed, key, idx, n_rows, t)
        parts.append(chunk_stats(x_true[idx.start : idx.stop], z))
    cat = {k: np.concatenate([p[k] for p in parts], axis=-1) for k in parts[0]}
    return x_true, cat


def simulate_point(params: PointParams, seed: int, key: tuple[int, ...], chunk_positions: int = 50) -> xr.Dataset:
    """Run one sweep point and return per-position statistics.

    Parameters
    ----------
    params : PointParams
        The sweep point.
    seed, key : int and tuple of int
        Config seed (>= 0) and the point's spawn key; positions use ``key + (0,)``, the
        trials of position j ``key + (1, j)``.
    chunk_positions : int, default 50
        Positions processed at once (memory/speed only; results do not depend on it), >= 1.

    Returns
    -------
    xarray.Dataset
        Dimensions ``estimator`` × ``position``: ``mse`` [m²], ``bias`` [m],
        ``sq_err_var`` [m⁴] (variance of the squared error, for Monte Carlo errors),
        clip counts, and ``crlb_var`` [m²] = 1/J(x).  In detail: ``mse``, ``bias``,
        ``sq_err_var`` over (estimator, position) with ``estimator`` = :data:`ESTIMATORS`;
        ``n_tdoa_no_solution``, ``n_tdoa_clipped``, ``n_aoa_clipped`` [1] (trial counts) and
        ``crlb_var`` over (position); coordinate ``x_true`` [m] (true train position); scalars
        ``d_m`` [m], ``sigma_tdoa_s`` [s], ``sigma_delta_m`` [m], ``sigma_aoa_rad`` [rad],
        ``n_trials`` [1], ``baseline_m`` [m].

    Raises
    ------
    ValueError
        If ``chunk_positions`` < 1 or ``seed`` is not a non-negative integer.
    """
    x_true, cat = run_positions(
        params, seed, key, 2, lambda xs, z: _chunk_stats(params, xs, z[0], z[1]), chunk_positions
    )
    return _point_dataset(params, x_true, cat)


def _point_dataset(params: PointParams, x_true: np.ndarray, cat: dict[str, np.ndarray]) -> xr.Dataset:
    """The dataset of :func:`simulate_point` from the true positions [m] and the per-position
    statistics of :func:`run_positions`; adds ``crlb_var`` [m²] = 1/J(x)."""
    geom = params.geometry
    crlb_var = 1.0 / fisher_information(x_true, params.sigma_delta_m, params.sigma_aoa_rad, geom)
    pos_dims = ("position",)
    ds = xr.Dataset(
        {
            "mse": (
                ("estimator", "position"),
                cat["mse"],
                {"units": "m2", "long_name": "mean squared position error over trials"},
            ),
            "bias": (
                ("estimator", "position"),
                cat["bias"],
                {"units": "m", "long_name": "mean position error over trials"},
            ),
            "sq_err_var": (
                ("estimator", "position"),
                cat["sq_err_var"],
                {"units": "m4", "long_name": "sample variance of the squared error over trials"},
            ),
            "n_tdoa_no_solution": (
                pos_dims,
                cat["n_tdoa_no_solution"].astype(np.int64),
                {"units": "1", "long_name": "trials with |range difference| >= baseline (no TDOA solution)"},
            ),
            "n_tdoa_clipped": (
                pos_dims,
                cat["n_tdoa_clipped"].astype(np.int64),
                {"units": "1", "long_name": "trials whose TDOA position was clipped to the cell segment"},
            ),
            "n_aoa_clipped": (
                pos_dims,
                cat["n_aoa_clipped"].astype(np.int64),
                {"units": "1", "long_name": "trials whose AOA position was clipped to the cell segment"},
            ),
            "crlb_var": (
                pos_dims,
                crlb_var,
                {"units": "m2", "long_name": "Cramer-Rao bound on the position variance, 1/J(x)"},
            ),
        },
        coords={
            "estimator": ("estimator", list(ESTIMATORS), {"units": "1", "long_name": "position estimator"}),
            "x_true": (pos_dims, x_true, {"units": "m", "long_name": "true train position along the track"}),
        },
    )
    scalars = {
        "d_m": (params.d_m, "m", "base-station distance from the track"),
        "sigma_tdoa_s": (params.sigma_tdoa_s, "s", "TDOA error standard deviation"),
        "sigma_delta_m": (params.sigma_delta_m, "m", "range-difference error standard deviation"),
        "sigma_aoa_rad": (params.sigma_aoa_rad, "rad", "AOA error standard deviation"),
        "n_trials": (params.n_trials, "1", "trials per position"),
        "baseline_m": (geom.baseline_m, "m", "distance between BS1 and BS2 along the track"),
    }
    for name, (val, units, long_name) in scalars.items():
        ds[name] = ((), val, {"units": units, "long_name": long_name})
    ds.attrs["point_params_json"] = repr(asdict(params))
    return ds


def summarize(ds: xr.Dataset) -> dict[str, float]:
    """RMSE per estimator over trials and positions, its Monte Carlo standard error, the
    aggregated CRLB and clip fractions, from a :func:`simulate_point` dataset.

    Parameters
    ----------
    ds : xarray.Dataset
        A dataset of :func:`simulate_point`.

    Returns
    -------
    dict of str to float
        For each estimator e of ``ds`` (:data:`ESTIMATORS`): ``rmse_<e>_m`` [m], the RMSE
        over trials and positions (source eq. 11), and ``rmse_<e>_se_m`` [m], its Monte Carlo
        standard error (from that of the mean squared error, to first order; 0 where the
        RMSE is 0); ``crlb_m`` [m], the square root of the mean over positions of
        ``crlb_var``; ``frac_tdoa_no_solution``, ``frac_tdoa_clipped``, ``frac_aoa_clipped``
        [1], the shares of all trials.
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
    out["crlb_m"] = float(np.sqrt(ds["crlb_var"].mean()))
    total = n_pos * n_trials
    for name in ("n_tdoa_no_solution", "n_tdoa_clipped", "n_aoa_clipped"):
        out[name.replace("n_", "frac_", 1)] = float(ds[name].sum()) / total
    return out


SUMMARY_ATTRS = {
    "crlb_m": ("m", "Cramer-Rao bound, sqrt(mean over positions of 1/J)"),
    "frac_tdoa_no_solution": ("1", "share of trials without TDOA solution"),
    "frac_tdoa_clipped": ("1", "share of trials with the TDOA position clipped"),
    "frac_aoa_clipped": ("1", "share of trials with the AOA position clipped"),
}


def sweep_dataset(points: list[xr.Dataset], parameter: str) -> xr.Dataset:
    """Collect sweep points into ``rmse`` [estimator, point] etc. along ``parameter``.

    Parameters
    ----------
    points : list of xarray.Dataset
        The datasets of :func:`simulate_point` of one sweep, at least one, in any order.
    parameter : str
        The swept SI variable of the points, the sweep's coordinate: ``"d_m"``,
        ``"sigma_tdoa_s"`` or ``"sigma_aoa_rad"`` (:data:`SWEEP_PARAMETER` of the config
        sweep name).

    Returns
    -------
    xarray.Dataset
        Dimensions ``estimator`` × ``parameter``, sorted by ``parameter`` (units of its
        attrs: m, s or rad): ``rmse`` and ``rmse_se`` [m] (position RMSE over trials and
        positions, source eq. 11, and its Monte Carlo standard error) over (estimator,
        parameter); ``crlb_m`` [m] (sqrt of the mean of 1/J over positions) and
        ``frac_tdoa_no_solution``, ``frac_tdoa_clipped``, ``frac_aoa_clipped`` [1] (shares of
        trials) over (parameter); and the other two of ``d_m`` [m], ``sigma_tdoa_s`` [s],
        ``sigma_aoa_rad`` [rad] over (parameter).
    """
    summaries = [summarize(p) for p in points]
    values = [float(p[parameter]) for p in points]
    ds = xr.Dataset(
        coords={
            parameter: (parameter, values, dict(points[0][parameter].attrs)),
            "estimator": ("estimator", list(ESTIMATORS), {"units": "1", "long_name": "position estimator"}),
        }
    )
    ds["rmse"] = (
        ("estimator", parameter),
        np.array([[s[f"rmse_{e}_m"] for s in summaries] for e in ESTIMATORS]),
        {"units": "m", "long_name": "position RMSE over trials and positions (source eq. 11)"},
    )
    ds["rmse_se"] = (
        ("estimator", parameter),
        np.array([[s[f"rmse_{e}_se_m"] for s in summaries] for e in ESTIMATORS]),
        {"units": "m", "long_name": "Monte Carlo standard error of the RMSE"},
    )
    for name, (units, long_name) in SUMMARY_ATTRS.items():
        ds[name] = ((parameter,), np.array([s[name] for s in summaries]), {"units": units, "long_name": long_name})
    for other in ("d_m", "sigma_tdoa_s", "sigma_aoa_rad"):
        if other != parameter:
            ds[other] = ((parameter,), np.array([float(p[other]) for p in points]), dict(points[0][other].attrs))
    return ds.sortby(parameter)
