"""Sensitivity cases of the nr study as the workflow schedules them (kept out of the
simulation code's fingerprint): each case's epochs, calibration epochs, shards, and which
estimate shards it reads.

A case is the ``nr`` config with a partial override merged in. It may shorten its runs:
its ``max_epochs`` caps the evaluation epochs (``nr.sensitivity.epochs``), its
``calibration.epochs`` the calibration run (at most the main run's). Every random draw is
keyed by (realization, epoch) or (realization, RRH), so the first n epochs of a longer run
with the same bursts are exactly a run of n epochs: a case that simulates the main run's
bursts (a tracker-only case) reads the main run's shards and cuts them.
"""

from __future__ import annotations

from typing import Any

from railradio.config import deep_merge, validate_config
from railradio.nr.engine.epochs import shard_epochs, shard_period
from railradio.nr.engine.simulate import scenario_from_config
from railradio.nr.study.workflow import sim_config


def merged_cases(nr_cfg: dict[str, Any], nr_schema: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Each sensitivity case as a whole nr config: the main nr config (without its
    ``sensitivity`` section) with the case's override merged in, validated against the nr
    section's schema (a bad value names ``nr.sensitivity.cases.<case>.<key>``).

    Parameters
    ----------
    nr_cfg : dict
        The validated ``nr`` section of the workflow config, with ``sensitivity.cases``.
    nr_schema : dict
        The JSON schema of the ``nr`` section.

    Returns
    -------
    dict of str to dict
        Case name -> its whole, validated nr config (config order).

    Raises
    ------
    railradio.config.ConfigError
        From :func:`railradio.config.validate_config` for an override that breaks the
        schema.
    """
    base = {k: v for k, v in nr_cfg.items() if k != "sensitivity"}
    return {
        case: validate_config(deep_merge(base, override), nr_schema, root=f"nr.sensitivity.cases.{case}")
        for case, override in nr_cfg["sensitivity"]["cases"].items()
    }


def case_epochs(case_cfg: dict, sens: dict) -> int:
    """Evaluation epochs of a case: ``sens["epochs"]``, fewer where the case sets
    ``max_epochs`` or its trajectory is shorter.

    Parameters
    ----------
    case_cfg : dict
        The case's merged nr config (:func:`merged_cases`).
    sens : dict
        The ``nr.sensitivity`` section (uses ``epochs``).

    Returns
    -------
    int
        Number of evaluation epochs (1, dt_s apart).
    """
    n = sens["epochs"] if case_cfg["max_epochs"] is None else min(sens["epochs"], case_cfg["max_epochs"])
    return min(n, scenario_from_config(case_cfg).trajectory.n_epochs)


def case_cal_epochs(case_cfg: dict, main_cfg: dict) -> int:
    """Calibration epochs of a case: its ``calibration.epochs``, at most the main run's.

    Parameters
    ----------
    case_cfg : dict
        The case's merged nr config.
    main_cfg : dict
        The main ``nr`` config.

    Returns
    -------
    int
        Number of calibration epochs (1).
    """
    return min(case_cfg["calibration"]["epochs"], main_cfg["calibration"]["epochs"])


def case_n_shards(case_cfg: dict, main_cfg: dict, sens: dict, real: str, n_cal_shards: int) -> int:
    """Shards of a case's own run (``real`` "cal" or "r0"): as many per epoch as a
    full-length case has, at least one.

    Parameters
    ----------
    case_cfg : dict
        The case's merged nr config.
    main_cfg : dict
        The main ``nr`` config.
    sens : dict
        The ``nr.sensitivity`` section (uses ``epochs`` and ``n_shards``).
    real : str
        ``"cal"`` (the calibration run) or anything else (``"r0"``, the evaluation run).
    n_cal_shards : int
        Shards of the main calibration run.

    Returns
    -------
    int
        Number of shards, in ``1..shards`` of a full-length run.
    """
    if real == "cal":
        n, n_full, shards = case_cal_epochs(case_cfg, main_cfg), main_cfg["calibration"]["epochs"], n_cal_shards
    else:
        n, n_full, shards = case_epochs(case_cfg, sens), sens["epochs"], sens["n_shards"]
    return max(1, min(shards, round(shards * n / n_full)))


def case_inputs(
    case: str, cases: dict, main_cfg: dict, sens: dict, real: str, n_main_epochs: int, n_cal_shards: int
) -> list[str]:
    """Estimate shards read by a case's calibration (``real="cal"``) or track (``"r0"``):
    the main run's shards covering the case's epochs when the case simulates the same
    bursts and needs no more epochs than the main run has, else those of the first case in
    ``cases`` (config order) with the same bursts and epochs, else the case's own.

    Parameters
    ----------
    case : str
        The case name (a key of ``cases``).
    cases : dict
        Case name -> merged nr config (:func:`merged_cases`), config order.
    main_cfg : dict
        The main ``nr`` config.
    sens : dict
        The ``nr.sensitivity`` section.
    real : str
        ``"cal"`` (calibration run) or ``"r0"`` (evaluation run).
    n_main_epochs : int
        Evaluation epochs of the main run.
    n_cal_shards : int
        Shards of the main calibration run.

    Returns
    -------
    list of str
        Paths of the estimate shards (``results/nr/.../estimates/<real>/s<k>.nc``), shard order.
    """
    cfg = cases[case]

    def epochs(c: dict) -> int:
        return case_cal_epochs(c, main_cfg) if real == "cal" else case_epochs(c, sens)

    n = epochs(cfg)
    if sim_config(cfg) == sim_config(main_cfg):
        n_main, n_sh = (
            (main_cfg["calibration"]["epochs"], n_cal_shards)
            if real == "cal"
            else (n_main_epochs, main_cfg["n_shards"])
        )
        if n <= n_main:
            return [
                f"results/nr/estimates/{real}/s{k}.nc"
                for k in range(n_sh)
                if shard_epochs(n_main, n_sh, k, shard_period(main_cfg))[0] < n
            ]
    owner = next(c for c, other in cases.items() if sim_config(other) == sim_config(cfg) and epochs(other) == n)
    n_sh = case_n_shards(cases[owner], main_cfg, sens, real, n_cal_shards)
    return [f"results/nr/cases/{owner}/estimates/{real}/s{k}.nc" for k in range(n_sh)]


def sync_sigma_s(case_cfg: dict) -> float:
    """RRH clock spread σ [s] of a case (0 without ``sync``).

    Parameters
    ----------
    case_cfg : dict
        The case's merged nr config (with its ``sync`` section).

    Returns
    -------
    float
        Standard deviation of the RRH clock offsets, s.
    """
    return float(case_cfg["sync"]["rrh_sigma_s"])
