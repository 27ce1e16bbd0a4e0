"""Published records: the paper-scale key numbers of a target that CI does not re-run.

Three nr targets cost more than the paper-scale reproduction in CI can absorb (its 90
minutes): the fidelity target (the exact reference, ~11 s an epoch), the reproduction map
(19 cells on a 1 000-epoch segment, about a third of the paper scale's job time) and the
sensitivity cases (27 cases, 14 with bursts of their own: another 30 %). Each is run on
purpose (``make fidelity``, ``make records``), and its key numbers are copied to
``paper/<name>_numbers.json`` beside ``paper/<name>_provenance.json``, which records what
produced them:

* ``code``: per workflow script of the target, :func:`railradio.codedeps.script_code_hash`
  (the script, every library module and data file it reaches, the pinned third-party
  versions), and per rule file, the SHA-256 of its tokens without comments (its params
  lambdas; :func:`railradio.codedeps.file_digest`), and of the library module computing
  those params (:mod:`railradio.nr.study.plan`, its syntax tree);
* ``config``: the config sections the target reads.

A record is *current* when both equal what is in the repository now. The key-number merge
reads a current record instead of re-running its target, and a test fails when a record is
stale — so a stale number can neither reach the paper nor pass CI.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from railradio.codedeps import file_digest, script_code_hash


@dataclass(frozen=True)
class Record:
    """A published record of a target's key numbers.

    Attributes
    ----------
    name : str
        The record's name: its files are ``paper/<name>_numbers.json`` and
        ``paper/<name>_provenance.json``.
    scripts : tuple of str
        The workflow scripts (repository-relative) whose code produced the numbers.
    inputs : callable
        ``inputs(config) -> dict``: the config sections the target reads, from the whole,
        validated workflow config.
    rule_files : tuple of str
        Rule files (repository-relative) whose code is recorded too (default none): the
        ``.smk`` files whose params the target's jobs get (tokens without comments), and the
        library modules that compute those params for them (e.g. ``railradio.nr.study.plan``;
        :func:`railradio.codedeps.file_digest`).
    """

    name: str
    scripts: tuple[str, ...]
    inputs: Callable[[dict[str, Any]], dict[str, Any]]
    rule_files: tuple[str, ...] = ()

    @property
    def numbers_file(self) -> str:
        """Repository-relative path of the published key numbers."""
        return f"paper/{self.name}_numbers.json"

    @property
    def provenance_file(self) -> str:
        """Repository-relative path of the record's provenance."""
        return f"paper/{self.name}_provenance.json"

    def provenance(self, root: Path, config: dict[str, Any]) -> dict[str, Any]:
        """``{"code": {path: hash}, "config": inputs(config)}`` for the repository at ``root``,
        as JSON would read it back (tuples as lists).

        Parameters
        ----------
        root : pathlib.Path
            The repository (or workflow copy) root.
        config : dict
            The whole workflow config, validated (defaults filled).

        Returns
        -------
        dict
            The provenance, JSON-normalized.
        """
        code = {s: script_code_hash(root / s) for s in self.scripts}
        code |= {f: hashlib.sha256(file_digest(root / f)).hexdigest()[:16] for f in self.rule_files}
        return json.loads(json.dumps({"code": code, "config": self.inputs(config)}))

    def stale(self, root: Path, config: dict[str, Any]) -> list[str]:
        """What differs between the published record and the repository at ``root``.

        Parameters
        ----------
        root : pathlib.Path
            The repository (or workflow copy) root.
        config : dict
            The whole workflow config, validated (defaults filled).

        Returns
        -------
        list of str
            Empty when the record is current; else ``"not published"``, or ``"code"`` and/or
            ``"config"`` (what changed since it was published).
        """
        if not ((root / self.numbers_file).exists() and (root / self.provenance_file).exists()):
            return ["not published"]
        recorded = json.loads((root / self.provenance_file).read_text(encoding="utf-8"))
        now = self.provenance(root, config)
        return [part for part in ("code", "config") if recorded.get(part) != now[part]]

    def fragment(self, root: Path, config: dict[str, Any], run_numbers: str) -> str:
        """The key-number fragment the merge reads: the record while it is current, else the
        run's own (the target then runs in this workflow).

        Parameters
        ----------
        root : pathlib.Path
            The repository (or workflow copy) root.
        config : dict
            The whole workflow config, validated (defaults filled).
        run_numbers : str
            The target's key-numbers file, relative to ``root``, that a run writes.

        Returns
        -------
        str
            ``numbers_file`` when :meth:`stale` is empty, else ``run_numbers``.
        """
        return run_numbers if self.stale(root, config) else self.numbers_file

    def publish(self, numbers_json: Path, root: Path, config: dict[str, Any]) -> None:
        """Copy a run's key numbers to ``root/paper`` with their provenance.

        Parameters
        ----------
        numbers_json : pathlib.Path
            The target's key numbers (a run at the config ``config``).
        root : pathlib.Path
            The repository root.
        config : dict
            The whole workflow config the run used, validated.
        """
        numbers = json.loads(Path(numbers_json).read_text(encoding="utf-8"))
        (root / self.numbers_file).write_text(json.dumps(numbers, indent=1, sort_keys=True) + "\n", encoding="utf-8")
        (root / self.provenance_file).write_text(
            json.dumps(self.provenance(root, config), indent=1, sort_keys=True) + "\n", encoding="utf-8"
        )
