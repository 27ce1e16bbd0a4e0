"""The nr study's jobs as the workflow plans them, computed once from the config.

:func:`nr_plan` derives from the validated ``nr`` section everything the nr rule files
(``workflow/rules/nr*.smk``, ``chain.smk``) need beyond the config's own values: the main
run's epochs and realizations, the simulation params, the sensitivity cases and the
reproduction map's cells (each merged with the nr section and validated, by the config
check, :func:`railradio.config_checks.check_config`, whose result it reuses), and which
estimate shards each case and cell reads. The result, :class:`NrPlan`, is frozen all the
way down: mappings are read-only (:class:`types.MappingProxyType`), sequences are tuples.

A rule's params get plain values (:func:`plain`): Snakemake re-runs a job when the
``repr`` of a param changes and leaves out of that comparison any value that is not a
builtin container (a read-only mapping would silently not count), so every param is a
plain ``dict``/``list``. No job script imports this module: a
change here re-runs exactly the jobs whose params or inputs it changes. The published
records of the map and the cases (:mod:`railradio.nr.study.records`), which hold no params,
record its code beside their rule files.
"""

from __future__ import annotations

import dataclasses
import numbers
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from railradio.nr.engine.simulate import Scenario, scenario_from_config
from railradio.nr.study import cases as nr_cases
from railradio.nr.study import reproduction_map as nr_map
from railradio.nr.study.workflow import receiver_selection, sim_config
from railradio.nr.tracking.measurement import MEASUREMENT_SETS

CAL_SHARDS = 2
"""Shards of the main run's calibration run (and the cap of a case's own)."""

MAP_RID = {"r0": 0, "cal": 1001}
"""The map's runs -> realization index of their random key: the segment is r0's, the
cells' calibration runs have their own key."""

RUNS = ("r0", "cal")
"""A case's or map cell's runs: the evaluation run (realization r0) and the calibration run."""

_SCALARS = (str, bytes, numbers.Number, type(None))


def _freeze(value: Any) -> Any:
    """A read-only copy: mappings as :class:`types.MappingProxyType`, lists and tuples as
    tuples, scalars as they are (any other type is refused: it could be mutable)."""
    if isinstance(value, Mapping):
        return MappingProxyType({k: _freeze(v) for k, v in value.items()})
    if isinstance(value, list | tuple):
        return tuple(_freeze(v) for v in value)
    if isinstance(value, _SCALARS):
        return value
    raise TypeError(f"an NrPlan holds mappings, sequences and scalars, not {type(value).__name__}")


def plain(value: Any) -> Any:
    """A fresh plain copy of a plan's value, as a rule's params or input get it.

    Parameters
    ----------
    value : object
        A field of :class:`NrPlan` or a part of one.

    Returns
    -------
    object
        Mappings as ``dict`` (same key order), tuples and lists as ``list``, scalars as they
        are: the types the config and the library's helpers give (YAML has no tuples).
    """
    if isinstance(value, Mapping):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    return value


@dataclass(frozen=True)
class NrPlan:
    """What the nr rule files need that is derived from the config (read-only).

    Built by :func:`nr_plan`; every field except ``scenario`` (itself frozen) is made
    read-only on construction (mappings -> :class:`types.MappingProxyType`, lists ->
    tuples). A "run" below is ``"r0"`` (the evaluation run of realization r0) or ``"cal"``
    (the calibration run). Epochs are 1 each, ``nr.trajectory.dt_s`` apart; paths are
    relative to the workflow directory.

    Attributes
    ----------
    scenario : Scenario
        The main run's scenario (:func:`railradio.nr.engine.simulate.scenario_from_config`).
    n_epochs : int
        Evaluation epochs of the main run: the trajectory's, at most ``nr.max_epochs``.
    realizations : tuple of str
        Realization names ``"r0"``, ``"r1"``, ... (``nr.realizations`` of them).
    n_cal_shards : int
        Shards of the main calibration run (:data:`CAL_SHARDS`).
    sim : mapping
        The simulation-defining sections of ``nr`` (:func:`railradio.nr.study.workflow.sim_config`).
    measurement_sets : tuple of str
        Measurement sets the main run tracks: all (``aod``, ``toa``, ``aod_toa``).
    selection : mapping of str to str
        Receiver name -> strength measure choosing its RRHs
        (:func:`railradio.nr.study.workflow.receiver_selection`).
    cases : mapping of str to mapping
        Sensitivity case -> the nr section with the case merged in, validated (config order).
    sens_base_epochs : int
        Epochs of the base run (r0 of the main run) the cases are compared with:
        ``nr.sensitivity.epochs``, at most the trajectory's.
    case_n_epochs : mapping of str to int
        Case -> its evaluation epochs (:func:`railradio.nr.study.cases.case_epochs`).
    case_n_cal_epochs : mapping of str to int
        Case -> its calibration epochs (:func:`railradio.nr.study.cases.case_cal_epochs`).
    case_n_shards : mapping of str to mapping of str to int
        Case -> run -> shards of the case's own run (:func:`railradio.nr.study.cases.case_n_shards`).
    case_inputs : mapping of str to mapping of str to tuple of str
        Case -> run -> estimate shards (netCDF paths) its calibration or track reads
        (:func:`railradio.nr.study.cases.case_inputs`).
    case_sim : mapping of str to mapping
        Case -> the simulation-defining sections of its config.
    case_selection : mapping of str to mapping of str to str
        Case -> receiver name -> strength measure choosing its RRHs.
    case_sync_sigma_s : mapping of str to float
        Case -> RRH clock spread σ, s (0 without clock errors).
    sweeps : mapping of str to mapping
        ``nr.sensitivity.sweeps``: sweep -> its cases, values and reference.
    unswept_cases : tuple of str
        The cases in no sweep (config order): the sensitivity figure's, beside the base.
    map_cells : mapping of str to mapping
        Reproduction-map cell -> its whole nr config, validated (map order).
    map_segment : tuple of int
        ``[first, end)`` epochs of r0 every map cell runs on.
    map_calibration : mapping
        The map cells' calibration run as an nr ``calibration`` section: ``epochs`` and its
        ``trajectory`` (``v0_m_s`` m/s, ``phases`` of [duration s, acceleration m/s²]).
    map_epochs : mapping of str to tuple of int
        Run -> ``[first, end)`` epochs a map shard simulates (the segment, or the
        calibration run's ``[0, epochs)``).
    map_n_shards : mapping of str to int
        Run -> shards of a map cell's run (``nr.map.n_shards`` for the segment, 1 for the
        calibration run).
    map_rid : mapping of str to int
        Run -> realization index of its random key (:data:`MAP_RID`).
    map_burst_config : mapping of str to mapping
        Cell -> what its bursts depend on (:func:`railradio.nr.study.reproduction_map.burst_config`).
    map_selection : mapping of str to mapping of str to str
        Cell -> receiver name -> strength measure choosing its RRHs.
    map_receivers : mapping of str to mapping of str to bool
        Cell -> the receivers it reports -> whether their trackers are gated.
    map_inputs : mapping of str to mapping of str to tuple of str
        Cell -> run -> estimate shards (netCDF paths) its tracker reads
        (:func:`railradio.nr.study.reproduction_map.shard_paths`).
    fidelity_real : str
        Realization whose shards the fidelity target samples (``r<nr.fidelity.realization>``).
    """

    scenario: Scenario
    n_epochs: int
    realizations: tuple[str, ...]
    n_cal_shards: int
    sim: Mapping[str, Any]
    measurement_sets: tuple[str, ...]
    selection: Mapping[str, str]
    cases: Mapping[str, Mapping[str, Any]]
    sens_base_epochs: int
    case_n_epochs: Mapping[str, int]
    case_n_cal_epochs: Mapping[str, int]
    case_n_shards: Mapping[str, Mapping[str, int]]
    case_inputs: Mapping[str, Mapping[str, tuple[str, ...]]]
    case_sim: Mapping[str, Mapping[str, Any]]
    case_selection: Mapping[str, Mapping[str, str]]
    case_sync_sigma_s: Mapping[str, float]
    sweeps: Mapping[str, Mapping[str, Any]]
    unswept_cases: tuple[str, ...]
    map_cells: Mapping[str, Mapping[str, Any]]
    map_segment: tuple[int, ...]
    map_calibration: Mapping[str, Any]
    map_epochs: Mapping[str, tuple[int, ...]]
    map_n_shards: Mapping[str, int]
    map_rid: Mapping[str, int]
    map_burst_config: Mapping[str, Mapping[str, Any]]
    map_selection: Mapping[str, Mapping[str, str]]
    map_receivers: Mapping[str, Mapping[str, bool]]
    map_inputs: Mapping[str, Mapping[str, tuple[str, ...]]]
    fidelity_real: str

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            if f.name != "scenario":
                object.__setattr__(self, f.name, _freeze(getattr(self, f.name)))


def _main_run(nr: dict[str, Any]) -> dict[str, Any]:
    scn = scenario_from_config(nr)
    n_traj = scn.trajectory.n_epochs
    return {
        "scenario": scn,
        "n_epochs": n_traj if nr["max_epochs"] is None else min(nr["max_epochs"], n_traj),
        "realizations": [f"r{i}" for i in range(nr["realizations"])],
        "n_cal_shards": CAL_SHARDS,
        "sim": sim_config(nr),
        "measurement_sets": list(MEASUREMENT_SETS),  # the main run tracks every measurement set (source §4)
        "selection": receiver_selection(nr),
        "fidelity_real": f"r{nr['fidelity']['realization']}",
    }


def _cases(nr: dict[str, Any], cases: dict[str, dict[str, Any]], n_traj: int, n_epochs: int) -> dict[str, Any]:
    sens = nr["sensitivity"]
    return {
        "cases": cases,
        "sens_base_epochs": min(sens["epochs"], n_traj),
        "case_n_epochs": {c: nr_cases.case_epochs(cfg, sens) for c, cfg in cases.items()},
        "case_n_cal_epochs": {c: nr_cases.case_cal_epochs(cfg, nr) for c, cfg in cases.items()},
        "case_n_shards": {
            c: {run: nr_cases.case_n_shards(cfg, nr, sens, run, CAL_SHARDS) for run in RUNS} for c, cfg in cases.items()
        },
        "case_inputs": {
            c: {run: nr_cases.case_inputs(c, cases, nr, sens, run, n_epochs, CAL_SHARDS) for run in RUNS} for c in cases
        },
        "case_sim": {c: sim_config(cfg) for c, cfg in cases.items()},
        "case_selection": {c: receiver_selection(cfg) for c, cfg in cases.items()},
        "case_sync_sigma_s": {c: nr_cases.sync_sigma_s(cfg) for c, cfg in cases.items()},
        "sweeps": sens["sweeps"],
        "unswept_cases": [c for c in cases if not any(c in sw["cases"] for sw in sens["sweeps"].values())],
    }


def _map(nr: dict[str, Any], cells: dict[str, dict[str, Any]], n_epochs: int) -> dict[str, Any]:
    mp = nr["map"]
    segment = [int(e) for e in mp["segment"]]
    calibration = nr_map.calibration_section(nr)
    receivers = nr_map.receivers(nr)
    return {
        "map_cells": cells,
        "map_segment": segment,
        "map_calibration": calibration,
        "map_epochs": {"r0": segment, "cal": [0, calibration["epochs"]]},
        "map_n_shards": {"r0": mp["n_shards"], "cal": 1},
        "map_rid": MAP_RID,
        "map_burst_config": {c: nr_map.burst_config(cfg) for c, cfg in cells.items()},
        "map_selection": {c: receiver_selection(cfg) for c, cfg in cells.items()},
        "map_receivers": {
            c: {rx: g for rx, g in receivers.items() if rx in nr_map.cell_receivers(c, nr)} for c in cells
        },
        "map_inputs": {c: {run: nr_map.shard_paths(c, run, cells, nr, n_epochs) for run in RUNS} for c in cells},
    }


def nr_plan(
    nr_cfg: dict[str, Any],
    nr_schema: dict[str, Any],
    cases: dict[str, dict[str, Any]] | None = None,
    map_cells: dict[str, dict[str, Any]] | None = None,
) -> NrPlan:
    """The nr study's plan, computed once from its validated config.

    Parameters
    ----------
    nr_cfg : dict
        The ``nr`` section of the workflow config, schema-valid with the defaults filled
        and passing :func:`railradio.config_checks.check_config`.
    nr_schema : dict
        The JSON schema of the ``nr`` section (used only for what is not passed in).
    cases : dict of str to dict, optional
        The merged, validated sensitivity cases (``check_config(...).nr_cases``); None:
        merge and validate them here (:func:`railradio.nr.study.cases.merged_cases`).
    map_cells : dict of str to dict, optional
        The validated map cells (``check_config(...).nr_map_cells``); None: build and
        validate them here (:func:`railradio.nr.study.reproduction_map.cells`).

    Returns
    -------
    NrPlan
        The plan, read-only (the given cases and cells are copied, not kept).
    """
    if cases is None:
        cases = nr_cases.merged_cases(nr_cfg, nr_schema)
    if map_cells is None:
        map_cells = nr_map.cells(nr_cfg, nr_schema)
    main = _main_run(nr_cfg)
    n_traj = main["scenario"].trajectory.n_epochs
    return NrPlan(
        **main, **_cases(nr_cfg, cases, n_traj, main["n_epochs"]), **_map(nr_cfg, map_cells, main["n_epochs"])
    )
