"""The published record of the fidelity target (``make fidelity``).

The exact reference costs ~14 s an epoch, so the shortcuts' measurement runs outside
``all``: ``make fidelity`` runs it at paper scale and copies its key numbers to
``paper/fidelity_numbers.json``, which every run's key-number merge reads. Beside them,
``paper/fidelity_provenance.json`` records what produced them — the code hash of the
fidelity scripts (every library module, data file and pinned third-party version they
reach, :func:`railradio.codedeps.script_code_hash`) and the config sections they read — so
that a test fails when either has changed since (the numbers would then be stale).

    python -m railradio.nr.fidelity_record publish results/nr/fidelity/key_numbers.json paper/
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

from railradio.codedeps import script_code_hash
from railradio.nr.workflow import sim_config

SCRIPTS = ("workflow/scripts/nr_fidelity/shard.py", "workflow/scripts/nr_fidelity/key_numbers.py")
NUMBERS = "fidelity_numbers.json"
PROVENANCE = "fidelity_provenance.json"


def inputs(config: dict[str, Any]) -> dict[str, Any]:
    """The config the fidelity target reads: the seed, the simulation sections of ``nr``,
    the main run's length and cell search, and ``nr.fidelity``."""
    nr = config["nr"]
    fidelity = {k: v for k, v in nr["fidelity"].items() if k != "n_shards"}  # how the work is split only
    return {
        "seed": config["seed"],
        "sim": sim_config(nr),
        "max_epochs": nr["max_epochs"],
        "cell_search": nr["cell_search"],
        "fidelity": fidelity,
    }


def provenance(root: Path, config: dict[str, Any]) -> dict[str, Any]:
    """``{"code": {script: hash}, "config": inputs(config)}`` for the repository at ``root``."""
    return {"code": {s: script_code_hash(root / s) for s in SCRIPTS}, "config": inputs(config)}


def publish(numbers_json: Path, paper_dir: Path, root: Path, config: dict[str, Any]) -> None:
    """Copy the fidelity key numbers to ``paper_dir`` with their provenance."""
    numbers = json.loads(Path(numbers_json).read_text(encoding="utf-8"))
    (paper_dir / NUMBERS).write_text(json.dumps(numbers, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    (paper_dir / PROVENANCE).write_text(
        json.dumps(provenance(root, config), indent=1, sort_keys=True) + "\n", encoding="utf-8"
    )


def main(argv: list[str] | None = None) -> int:
    import yaml

    args = sys.argv[1:] if argv is None else argv
    if len(args) != 3 or args[0] != "publish":
        print(__doc__, file=sys.stderr)
        return 2
    root = Path.cwd()
    config = yaml.safe_load((root / "config/config.yaml").read_text(encoding="utf-8"))
    from railradio.config import load_schema, validate_config

    validate_config(config, load_schema(root / "workflow/schemas/config.schema.yaml"))  # fills the defaults
    publish(Path(args[1]), Path(args[2]), root, config)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
