"""Reproducible random number generators.

Every random draw in railradio comes from an explicit :class:`numpy.random.Generator`.
A job derives its generator from the config seed and *stable integer IDs* (study,
sweep, sweep point, shard, ...) through :class:`numpy.random.SeedSequence`, never from
job order, so the same config gives identical results whatever ``snakemake -j``.

Study IDs are the source papers' numbers (000 nr, 002 fusion, 003 tunnel, 004 handover).  IDs of things that
are described by parameter values (a sweep point) come from :func:`stable_id`, a hash of
their canonical JSON: the same physical point gets the same random numbers wherever it
appears (common random numbers across a sweep and the reference point).
"""

from __future__ import annotations

import hashlib
import json
from typing import Any

import numpy as np

STUDY_IDS: dict[str, int] = {"nr": 0, "fusion": 2, "tunnel": 3, "handover": 4}
"""Stable integer ID of each study (the source paper's number)."""


def canonical_json(obj: Any) -> str:
    """Canonical JSON text of ``obj``: sorted keys, no whitespace, floats by ``repr``."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False)


def stable_id(obj: Any) -> int:
    """A stable 32-bit integer ID of a JSON-serializable value.

    Parameters
    ----------
    obj
        Any JSON-serializable value (a dict of sweep-point parameters, a string).

    Returns
    -------
    int
        The first 4 bytes of the SHA-256 of :func:`canonical_json` of ``obj``, in
        ``[0, 2**32)``.  Independent of Python's hash seed and of the machine.
    """
    digest = hashlib.sha256(canonical_json(obj).encode("utf-8")).digest()
    return int.from_bytes(digest[:4], "little")


def spawn_key(study: str, *ids: int) -> tuple[int, ...]:
    """The SeedSequence spawn key of a job: ``(study ID, *ids)``.

    Raises
    ------
    ValueError
        If ``study`` is unknown or an ID is not a non-negative integer.
    """
    if study not in STUDY_IDS:
        raise ValueError(f"study must be one of {sorted(STUDY_IDS)}, got {study!r}")
    key = (STUDY_IDS[study], *ids)
    for k in key:
        if not isinstance(k, (int, np.integer)) or k < 0:
            raise ValueError(f"spawn-key IDs must be non-negative integers, got {key!r}")
    return tuple(int(k) for k in key)


def make_rng(seed: int, key: tuple[int, ...]) -> np.random.Generator:
    """A PCG64 generator for ``(seed, key)``.

    Parameters
    ----------
    seed
        The config's master seed, a non-negative integer.
    key
        The job's spawn key (:func:`spawn_key`), extended with sub-IDs as needed.
    """
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(int(seed), spawn_key=key)))
