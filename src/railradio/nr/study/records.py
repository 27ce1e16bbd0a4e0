"""The nr study's published records (:mod:`railradio.published`): the fidelity target, the
reproduction map and the sensitivity cases, each run on purpose at paper scale (``make
fidelity``, ``make records``) and read by the key-number merge while current.

    python -m railradio.nr.study.records publish fidelity results/nr/fidelity/key_numbers.json
    python -m railradio.nr.study.records publish map results/nr/map/key_numbers.json
    python -m railradio.nr.study.records publish cases results/nr/cases/key_numbers.json

(from the repository root; the record is written to ``paper/`` for the config in
``config/config.yaml``).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

from railradio.nr.study.workflow import sim_config
from railradio.published import Record


def fidelity_inputs(config: dict[str, Any]) -> dict[str, Any]:
    """The config the fidelity target reads: the seed, the simulation sections of ``nr``,
    the main run's length and cell search, and ``nr.fidelity`` (but how its work is split).

    Parameters
    ----------
    config : dict
        The whole workflow config, validated.

    Returns
    -------
    dict
        ``seed``, ``sim``, ``max_epochs``, ``cell_search`` and ``fidelity``.
    """
    nr = config["nr"]
    fidelity = {k: v for k, v in nr["fidelity"].items() if k != "n_shards"}
    return {
        "seed": config["seed"],
        "sim": sim_config(nr),
        "max_epochs": nr["max_epochs"],
        "cell_search": nr["cell_search"],
        "fidelity": fidelity,
    }


def _nr_target_inputs(config: dict[str, Any], own: str, other: str) -> dict[str, Any]:
    """The seed and ``nr`` without the ``other`` target's section, the fidelity target and
    the shard counts (``nr.n_shards`` and ``nr.<own>.n_shards``)."""
    nr = {k: v for k, v in config["nr"].items() if k not in (other, "fidelity", "n_shards")}
    nr[own] = {k: v for k, v in nr[own].items() if k != "n_shards"}
    return {"seed": config["seed"], "nr": nr}


def map_inputs(config: dict[str, Any]) -> dict[str, Any]:
    """The config the reproduction map reads: the seed and the whole ``nr`` section but the
    sensitivity cases, the fidelity target and how the work is split into shards (results do
    not depend on it). Wider than what the map's cells use, so that a record is never
    taken for current when it is not.

    Parameters
    ----------
    config : dict
        The whole workflow config, validated.

    Returns
    -------
    dict
        ``seed`` and ``nr``.
    """
    return _nr_target_inputs(config, "map", "sensitivity")


def cases_inputs(config: dict[str, Any]) -> dict[str, Any]:
    """The config the sensitivity cases read: the seed and the whole ``nr`` section but the
    reproduction map, the fidelity target and the shard counts (each case is the ``nr``
    config with its override merged in, and its key numbers are paired with the main
    run's r0 track).

    Parameters
    ----------
    config : dict
        The whole workflow config, validated.

    Returns
    -------
    dict
        ``seed`` and ``nr``.
    """
    return _nr_target_inputs(config, "sensitivity", "map")


FIDELITY = Record(
    "fidelity",
    ("workflow/scripts/nr_fidelity/shard.py", "workflow/scripts/nr_fidelity/key_numbers.py"),
    fidelity_inputs,
)
"""The fidelity target (``make fidelity``; rule ``nr_fidelity``)."""

MAP = Record(
    "map",
    (
        "workflow/scripts/nr/shard.py",  # the default cell's segment is the main run's r0
        "workflow/scripts/nr_map/shard.py",
        "workflow/scripts/nr_map/cell.py",
        "workflow/scripts/nr_map/key_numbers.py",
    ),
    map_inputs,
    # the rule file's params and inputs, and the plan they read (its cells, runs and shards)
    rule_files=("workflow/rules/nr_map.smk", "src/railradio/nr/study/plan.py"),
)
"""The reproduction map (``make records``; rule ``nr_map_key_numbers``)."""

CASES = Record(
    "cases",
    (
        "workflow/scripts/nr/shard.py",  # the cases' own bursts, and the main run's they re-use
        "workflow/scripts/nr/calibrate.py",  # the main run's r0 track, the cases' reference
        "workflow/scripts/nr/track.py",
        "workflow/scripts/nr/case_calibrate.py",
        "workflow/scripts/nr/case_track.py",
        "workflow/scripts/nr/case_key_numbers.py",
    ),
    cases_inputs,
    # the rule file's params and inputs, and the plan they read (the cases' epochs, shards, inputs)
    rule_files=("workflow/rules/nr.smk", "src/railradio/nr/study/plan.py"),
)
"""The nr sensitivity cases (``make records``; rule ``nr_case_key_numbers``)."""

RECORDS = {r.name: r for r in (FIDELITY, MAP, CASES)}


def main(argv: list[str] | None = None) -> int:
    """``publish <record> <key_numbers.json>``: write the record for ``config/config.yaml``.

    Run from the repository root: the config and its schema are read from there and the
    record is written to its ``paper/`` directory.

    Parameters
    ----------
    argv : list of str or None, default None
        The command-line arguments without the program name: ``publish``, a record name
        (``fidelity``, ``map`` or ``cases``) and the path of the run's key-number JSON file;
        None reads ``sys.argv[1:]``.

    Returns
    -------
    int
        Exit status: 0 once the record is written, 2 for wrong arguments (the module
        docstring is printed to stderr as the usage).

    Raises
    ------
    railradio.config.ConfigError
        If ``config/config.yaml`` breaks the schema.
    OSError
        If the config, the schema or the key-number file cannot be read, or the record
        cannot be written.
    """
    import yaml

    from railradio.config import load_schema, validate_config

    args = sys.argv[1:] if argv is None else argv
    if len(args) != 3 or args[0] != "publish" or args[1] not in RECORDS:
        print(__doc__, file=sys.stderr)
        return 2
    root = Path.cwd()
    config = yaml.safe_load((root / "config/config.yaml").read_text(encoding="utf-8"))
    validate_config(config, load_schema(root / "workflow/schemas/config.schema.yaml"))  # fills the defaults
    RECORDS[args[1]].publish(Path(args[2]), root, config)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
