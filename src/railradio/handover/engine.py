"""The vectorized engine: blocks of crossings → per-handover outcomes (NetCDF-ready).

A *block* is ``runs_per_block`` train crossings with their own spawn keys
(:func:`railradio.handover.model.block_keys`); a shard (Snakemake job) is a contiguous range
of blocks, so results never depend on how blocks are grouped into shards.  Every policy
sees the same draws (common random numbers).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from railradio.handover.model import build_context, draw_block
from railradio.handover.params import Scenario
from railradio.handover.policies import make_policy, run_policy
from railradio.handover.train import kinematics


def simulate_block(
    scn: Scenario,
    speed_kmh: float,
    seed: int,
    block: int,
    n_runs: int,
    policies: tuple[str, ...],
    stream: str = "sweep",
) -> dict[str, dict[str, tuple]]:
    """Outcomes of every policy on one block: policy -> name -> (dims, array, units, long_name).

    Parameters
    ----------
    scn : Scenario
        The scenario; the joint policy needs ``scn.joint.m`` and ``scn.joint.alpha`` set.
    speed_kmh : float
        Train speed [km/h], 1 ≤ v ≤ 1000.
    seed : int
        Root seed of the study's random numbers.
    block : int
        Block index (≥ 0); with ``speed_kmh`` and ``stream`` it selects the spawn keys.
    n_runs : int
        Train crossings in the block (≥ 1).
    policies : tuple of str
        Registered policy names (``joint``, ``a3``, ``distance``), all run on the same draws.
    stream : str, optional
        Random stream, ``sweep`` (evaluation runs, default) or ``cost`` (cost-grid runs).

    Returns
    -------
    dict of str to dict of str to tuple
        Per policy, :func:`railradio.handover.policies.run_policy`'s outcomes: name ->
        (dims, array, units, long_name), arrays [n_runs, N] over ("run", "node") (a few joint
        extras over ("run",)).

    Raises
    ------
    ValueError
        If the speed is outside 1–1000 km/h, ``block`` is negative, ``n_runs`` < 1,
        ``stream`` or a policy name is unknown, or the joint policy's (m, α) are not set.
    """
    kin = kinematics(scn, speed_kmh)
    draws = draw_block(seed, speed_kmh, block, n_runs, kin, scn.train.n_nodes, stream)
    ctx = build_context(scn, kin, draws)
    return {p: run_policy(make_policy(p), ctx) for p in policies}


def _concat(parts: list[dict[str, tuple]]) -> dict[str, tuple]:
    out = {}
    for name, (dims, _, units, long_name) in parts[0].items():
        out[name] = (dims, np.concatenate([p[name][1] for p in parts], axis=0), units, long_name)
    return out


def simulate_blocks(
    scn: Scenario,
    speed_kmh: float,
    seed: int,
    blocks: range,
    runs_per_block: int,
    policies: tuple[str, ...],
    stream: str = "sweep",
) -> xr.Dataset:
    """Per-handover outcomes of ``blocks`` at one speed, as a dataset over (run, node)
    per policy (variables ``<policy>__<name>``).

    Parameters
    ----------
    scn : Scenario
        The scenario; the joint policy needs ``scn.joint.m`` and ``scn.joint.alpha`` set.
    speed_kmh : float
        Train speed [km/h], 1 ≤ v ≤ 1000.
    seed : int
        Root seed of the study's random numbers.
    blocks : range
        Contiguous, non-empty range of block indices (≥ 0), e.g. from :func:`shard_blocks`.
    runs_per_block : int
        Train crossings per block (≥ 1).
    policies : tuple of str
        Registered policy names (``joint``, ``a3``, ``distance``), all run on the same draws.
    stream : str, optional
        Random stream, ``sweep`` (evaluation runs, default) or ``cost`` (cost-grid runs).

    Returns
    -------
    xarray.Dataset
        Variables ``<policy>__<name>`` with ``units`` and ``long_name`` attributes, mostly over
        dims (``run``, ``node``): e.g. ``success`` [1], ``attempts`` [1], ``pingpong`` [1],
        ``delay_s``, ``delay_all_s``, ``delay_trigger_s``, ``command_time_s`` [s],
        ``command_x_m``, ``completion_x_m`` [m], ``rsrp_gap_db`` [dB]; the joint policy adds
        band and fit variables over (``run``,).  Coordinates ``run`` (global crossing index
        block·runs_per_block + j) and ``node`` (1 = head); scalar ``speed_kmh`` [km/h];
        attribute ``policies`` (comma-separated).

    Raises
    ------
    ValueError
        If ``blocks`` is empty, or for the reasons listed under :func:`simulate_block`.
    """
    if len(blocks) == 0:
        raise ValueError("blocks must not be empty")
    per_policy: dict[str, list] = {p: [] for p in policies}
    for b in blocks:
        res = simulate_block(scn, speed_kmh, seed, b, runs_per_block, policies, stream)
        for p in policies:
            per_policy[p].append(res[p])
    data_vars = {}
    for p in policies:
        for name, (dims, arr, units, long_name) in _concat(per_policy[p]).items():
            data_vars[f"{p}__{name}"] = xr.Variable(dims, arr, {"units": units, "long_name": f"{p}: {long_name}"})
    runs = np.arange(blocks[0] * runs_per_block, blocks[-1] * runs_per_block + runs_per_block)
    coords = {
        "run": ("run", runs, {"units": "1", "long_name": "global crossing index (block*runs_per_block + j)"}),
        "node": ("node", np.arange(scn.train.n_nodes) + 1, {"units": "1", "long_name": "relay-AP node (1 = head)"}),
    }
    ds = xr.Dataset(data_vars, coords=coords)
    ds["speed_kmh"] = xr.Variable((), float(speed_kmh), {"units": "km/h", "long_name": "train speed"})
    ds.attrs["policies"] = ",".join(policies)
    return ds


def shard_blocks(n_blocks: int, n_batches: int, batch: int) -> range:
    """The contiguous blocks of shard ``batch`` of ``n_batches`` (as even as possible).

    Parameters
    ----------
    n_blocks : int
        Total number of blocks of crossings at one speed.
    n_batches : int
        Number of shards (Snakemake jobs), 1 ≤ n_batches ≤ n_blocks.
    batch : int
        Index of this shard, 0 ≤ batch < n_batches.

    Returns
    -------
    range
        Block indices of the shard; the shards of all batches partition 0…n_blocks − 1.

    Raises
    ------
    ValueError
        If ``n_batches`` is not in 1..n_blocks or ``batch`` not in 0..n_batches − 1.
    """
    if not 1 <= n_batches <= n_blocks:
        raise ValueError(f"n_batches must be in 1..n_blocks={n_blocks}, got {n_batches!r}")
    if not 0 <= batch < n_batches:
        raise ValueError(f"batch must be in 0..{n_batches - 1}, got {batch!r}")
    edges = [n_blocks * j // n_batches for j in range(n_batches + 1)]
    return range(edges[batch], edges[batch + 1])


def speed_label(speed_kmh: float) -> str:
    """Wildcard text of a speed: ``350`` or ``312.5``.

    Parameters
    ----------
    speed_kmh : float
        Train speed [km/h].

    Returns
    -------
    str
        The speed in ``%g`` format (no trailing ``.0``), used in file names and wildcards.
    """
    return f"{float(speed_kmh):g}"
