"""The reproduction map's cells that share one synthesis per epoch, each synthesized on its
own against the one synthesis (:func:`railradio.nr.engine.equivalence.compare_variants`):
which decisions the shared synthesis changes.

    python -m railradio.nr.study.map_equivalence --first 1500 --epochs 100 --out eq_map.json

(from the repository root; the map's cells as ``config/config.yaml`` and its schema give them).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import yaml

from railradio.nr.engine.equivalence import compare_variants
from railradio.nr.engine.simulate import Scenario, scenario_from_config
from railradio.nr.engine.variants import variant_groups
from railradio.nr.study.reproduction_map import burst_config, calibration_owner
from railradio.rng import spawn_key


def map_variants(cfg: dict, schema: dict) -> tuple[list[Scenario], list[str]]:
    """The map's largest group of cells with their own bursts that differ only in amplitudes
    or receivers (as ``workflow/rules/nr_map.smk`` runs them).

    Parameters
    ----------
    cfg : dict
        The whole workflow config (validated here).
    schema : dict
        The config schema.

    Returns
    -------
    tuple
        (the cells' scenarios, their names).
    """
    from railradio.config import validate_config
    from railradio.config_checks import check_config

    validate_config(cfg, schema)
    cells = check_config(cfg, schema).nr_map_cells
    owners = {c: burst_config(v) for c, v in cells.items() if calibration_owner(c, cells) == c}
    group = max(variant_groups(owners), key=len, default=[])
    return [scenario_from_config(owners[c]) for c in group], group


def main(argv: list[str] | None = None) -> None:  # pragma: no cover - command line
    """Command line: ``--first``, ``--epochs`` (consecutive, realization 0), ``--out``."""
    from railradio.config import load_schema

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--first", type=int, default=1500)
    ap.add_argument("--epochs", type=int, default=100)
    ap.add_argument("--out", default=None)
    a = ap.parse_args(argv)
    root = Path.cwd()
    cfg = yaml.safe_load((root / "config/config.yaml").read_text(encoding="utf-8"))
    scns, cells = map_variants(cfg, load_schema(root / "workflow/schemas/config.schema.yaml"))
    epochs = np.arange(a.first, a.first + a.epochs)
    res = compare_variants(scns, cfg["seed"], spawn_key("nr", 0), epochs) | {"cells": cells}
    text = json.dumps(res, indent=2)
    if a.out:
        Path(a.out).write_text(text + "\n", encoding="utf-8")
    print(text)


if __name__ == "__main__":  # pragma: no cover
    main()
