"""The nr study's epochs through the burst engine: a shard of one realization's track ->
its per-cell estimates (:func:`simulate_epochs`), and how a run's epochs are split into
shards (:func:`shard_epochs`, each shard starting on an acquisition epoch).

Every random draw is keyed by (realization, epoch) or (realization, RRH), and the
receiver's state restarts at fixed acquisition epochs, so the result of an epoch does not
depend on the shard it falls in. The bursts come from
:class:`railradio.nr.engine.SpectralSynthesis` (truth -> burst on the correlation's lag grid)
and are measured by :class:`railradio.nr.engine.SharedEstimator` (burst + deployment + its
own state -> measurements; it never receives the truth). Both give the decisions of the
reference path (:class:`railradio.nr.engine.simulate.Synthesis`, :class:`railradio.nr.engine.simulate.Estimator`)
on the same draws: :mod:`railradio.nr.engine.equivalence` counts what differs.
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np
import xarray as xr

from railradio.nr.engine.estimates_dataset import EpochRecord, estimates_dataset
from railradio.nr.engine.estimator import SharedEstimator
from railradio.nr.engine.frontend import SpectralSynthesis
from railradio.nr.engine.simulate import Scenario
from railradio.nr.receiver.cellsearch import CellSearchConfig

PROGRESS_EVERY_S = 30.0
"""At most this long between two progress lines of :func:`simulate_epochs` (s of wall time)."""

_log = logging.getLogger("railradio.nr")


class _Progress:
    """Epochs done, rate and ETA, logged at most every ``every_s`` seconds and at the end."""

    def __init__(self, total: int, every_s: float):
        self.total, self.every_s = total, every_s
        self.t0 = self.last = time.monotonic()

    def __call__(self, done: int, bursts: int) -> None:
        now = time.monotonic()
        if now - self.last < self.every_s and done < self.total:
            return
        self.last = now
        rate = done / max(now - self.t0, 1e-9)
        eta = (self.total - done) / rate if rate > 0 else float("inf")
        _log.info(
            "epochs %d/%d (%d bursts with warm-up), %.2f epochs/s, %.0f s elapsed, ETA %.0f s",
            done,
            self.total,
            bursts,
            rate,
            now - self.t0,
            eta,
        )


def simulate_epochs(
    scn: Scenario,
    epochs: np.ndarray,
    seed: int,
    key: tuple[int, ...],
    keep_corr_epochs: tuple[int, ...] = (),
    progress_every_s: float = PROGRESS_EVERY_S,
) -> xr.Dataset:
    """Simulate the given epochs of one realization.

    Synthesis (truth -> burst) and estimation (burst -> measurements) are separate; the truth
    of each epoch is kept only to score. Epochs since the last fixed acquisition epoch before
    each requested one are replayed first (:func:`railradio.nr.receiver.cellsearch.warmup_start`), so
    an epoch's result does not depend on which other epochs are requested; a shard from
    :func:`shard_epochs` starts on an acquisition epoch and replays none. Progress (epochs
    done, rate, ETA) goes to the ``railradio.nr`` logger at most every ``progress_every_s``.

    Parameters
    ----------
    scn : Scenario
        The scenario.
    epochs : array_like of int
        Epoch indices (t = epoch · dt, dt = ``scn.trajectory.dt_s`` in s); strictly increasing.
    seed, key : int, tuple of int
        Config seed and the realization's spawn key.
    keep_corr_epochs : tuple of int
        Epochs whose per-block correlation functions are kept (for inspection; only the
        first of them is stored, as ``corr_sample``).
    progress_every_s : float
        Longest wall time between two progress lines, s.

    Returns
    -------
    xarray.Dataset
        Dimensions ``epoch`` × ``cand`` (the receiver's neighbour list, its anchor cell
        first): truth (position, speed, acceleration; per candidate 3-D distance, AOD,
        delay, received power) and estimates (candidate list, SS-RSRP, detections, AOD,
        TOA, combined peak), the latter per ``receiver``: e.g. ``toa_hat`` [s] and ``aod_hat``
        [rad] with dims (``receiver``, ``epoch``, ``cand``); ``toa_true`` [s], ``aod_true`` [rad],
        ``ss_rsrp`` and ``rx_power`` per (``epoch``, ``cand``); ``x_true`` [m], ``v_true`` [m/s],
        ``a_true`` [m/s²], ``t`` [s], ``sir_best`` [dB] per ``epoch``.

    Raises
    ------
    ValueError
        When ``epochs`` is not strictly increasing, or (from the synthesis / the estimator)
        when a decimation setting does not divide the front end's.
    """
    epochs = np.asarray(epochs, dtype=np.int64)
    if np.any(np.diff(epochs) <= 0):
        raise ValueError("epochs must be strictly increasing")
    dep = scn.deployment
    synth = SpectralSynthesis(scn, seed, key)
    est = SharedEstimator(scn, on_lag_grid=True)
    n_c = min(scn.cell_search.n_neighbours, dep.n_rrh)
    rec = EpochRecord.empty(len(est.receivers), epochs.size, n_c)
    progress, bursts = _Progress(epochs.size, progress_every_s), 0
    for i, e in enumerate(epochs):
        for w in range(est.start(int(e)), int(e)):  # warm-up: the cell search's state at e
            b = synth(w)
            est(w, b.z, b.s_min, report=False)
            bursts += 1
        b = synth(int(e))
        m = est(int(e), b.z, b.s_min, keep_corr=int(e) in keep_corr_epochs)
        rec.record(i, int(e), b, m, dep)
        bursts += 1
        progress(i + 1, bursts)
    return estimates_dataset(scn, epochs, [name for name, _, _ in est.receivers], rec)


def shard_period(nr: dict) -> int:
    """The epochs between two points where the receiver's state restarts (the cell search's
    fixed acquisitions and the network's serving-cell restarts): the period shards are
    aligned to.

    Parameters
    ----------
    nr : dict
        The ``nr`` section of the config (``cell_search.acquire_every`` — its default when
        absent — and ``traffic.serving_reset_every``).

    Returns
    -------
    int
        lcm(acquire_every, serving_reset_every), epochs.
    """
    acquire = int(nr.get("cell_search", {}).get("acquire_every", CellSearchConfig().acquire_every))
    return math.lcm(acquire, int(nr["traffic"]["serving_reset_every"]))


def shard_epochs(n_epochs: int, n_shards: int, shard: int, period: int = 1) -> np.ndarray:
    """Epoch indices of one shard: contiguous, near-equal blocks whose boundaries are
    multiples of ``period`` (so each shard starts where the receiver's state restarts and
    replays no warm-up), unless that would leave a shard empty (then near-equal blocks).

    Parameters
    ----------
    n_epochs : int
        Epochs of the whole run.
    n_shards : int
        Number of shards.
    shard : int
        Shard index, in ``0..n_shards - 1``.
    period : int
        The boundaries' period, epochs (:func:`shard_period`; 1: none).

    Returns
    -------
    numpy.ndarray
        The shard's epoch indices (int, increasing).

    Raises
    ------
    ValueError
        When ``shard`` is outside ``0..n_shards - 1`` or ``period`` < 1.
    """
    if not 0 <= shard < n_shards:
        raise ValueError(f"shard must be in 0..{n_shards - 1}, got {shard!r}")
    if period < 1:
        raise ValueError(f"period must be >= 1, got {period!r}")
    edges = np.linspace(0, n_epochs, n_shards + 1)
    aligned = np.minimum((edges / period).round().astype(int) * period, n_epochs)
    aligned[-1] = n_epochs
    edges = aligned if np.all(np.diff(aligned) > 0) else edges.round().astype(int)
    return np.arange(edges[shard], edges[shard + 1])
