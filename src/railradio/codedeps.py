"""The library code a workflow script runs, found by reading imports (no execution).

Snakemake re-runs a rule when its script changes, not when a module the script imports
changes. :func:`script_code_hash` closes that gap: it walks the script's ``import``
statements (its abstract syntax tree) transitively through ``railradio`` and through the
helper modules beside the script, and hashes every file reached. The workflow sets the
hash as each rule's ``code`` param, so a rule re-runs exactly when code it runs changes.

What counts as reached, from a file F:

* every ``import railradio.x`` / ``from railradio.x import y`` anywhere in F (also inside
  functions: a conditional import is counted, which can only re-run a rule too often);
  ``y`` counts when it is a module; a module's parent packages (their ``__init__.py``)
  count, because importing the module runs them;
* for a workflow script, ``import helper`` of a ``helper.py`` beside it (or, failing that,
  in exactly one other script directory), and a string literal naming a sibling script
  (``"track.py"``, run through :mod:`runpy`);
* a package data file (``railradio/data/<name>``) whose name appears as a string literal.

Third-party packages are not followed into their source: the hash holds the installed
version of each distribution the reached files import, so upgrading numpy re-runs the
rules that use it and nothing else.

What of a file counts (:func:`file_digest`): of Python source, its syntax tree without
docstrings and other string-only statements (attribute notes), so that a comment, a
docstring, an attribute note or a reformatting re-runs nothing; of a Snakemake rule file,
its tokens without comments; of any other file, its bytes. The tree's printed form is the
interpreter's, so the hash also holds the Python minor version.
"""

from __future__ import annotations

import ast
import hashlib
import io
import sys
import time
import tokenize
from functools import cache, lru_cache
from pathlib import Path

PACKAGE = "railradio"
SRC_ROOT = Path(__file__).resolve().parent
"""The ``railradio`` package directory."""
DATA_DIR = SRC_ROOT / "data"


def module_path(name: str, root: Path = SRC_ROOT) -> Path | None:
    """The file of ``railradio`` module ``name`` (a package: its ``__init__.py``), or None.

    Parameters
    ----------
    name : str
        Dotted module name, e.g. ``"railradio.fusion.arc"``.
    root : pathlib.Path, default SRC_ROOT
        The ``railradio`` package directory to resolve modules and package data against.

    Returns
    -------
    pathlib.Path or None
        ``<root>/<sub>/__init__.py`` for a package or ``<root>/<sub>.py`` for a module; None
        if ``name`` is not under ``railradio`` or names no file (e.g. a function imported
        with ``from railradio.x import y``).

    Notes
    -----
    Directories are listed once per process (:func:`clear_caches` forgets the listings).
    """
    return _module_path(name, root)


@cache
def _module_path(name: str, root: Path) -> Path | None:
    """:func:`module_path`, from the directory listings (:func:`_listing`) once per process."""
    parts = name.split(".")
    if parts[0] != PACKAGE:
        return None
    base = root.joinpath(*parts[1:])
    if "__init__.py" in _listing(base):
        return base / "__init__.py"
    if f"{base.name}.py" in _listing(base.parent):
        return base.with_suffix(".py")
    return None


def _parents(name: str) -> list[str]:
    parts = name.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts))]


def _facts(path: Path) -> tuple[tuple[str, ...], frozenset[str]]:
    """(dotted names imported, string literals) of one file, cached while it is unchanged."""
    names, strings, relative, _ = _python_source(path)
    if relative:
        raise ValueError(f"{path}: relative imports are not supported (use railradio.…)")
    return names, strings


def _python_source(path: Path) -> tuple[tuple[str, ...], frozenset[str], bool, bytes]:
    """One parse of a Python file, cached while its content is unchanged: (dotted names
    imported, string literals, whether it imports relatively, :func:`file_digest`'s form).
    The parse is cached on the bytes themselves. A file whose status (time stamp, size,
    inode) was seen before is not read again, unless its time stamp is under
    :data:`_RACY_NS` old: two writes within the file system's clock tick can share a time
    stamp and a size (Git's "racy clean" entries, handled alike)."""
    st = path.stat()
    key = (str(path), st.st_mtime_ns, st.st_size, st.st_ino)
    if key in _BY_STATUS and time.time_ns() - st.st_mtime_ns > _RACY_NS:
        return _BY_STATUS[key]
    out = _python_source_cached(str(path), path.read_bytes())
    _BY_STATUS[key] = out
    return out


_RACY_NS = 2_000_000_000
"""How old a file's time stamp must be before its status alone identifies its content, ns."""
_BY_STATUS: dict[tuple[str, int, int, int], tuple[tuple[str, ...], frozenset[str], bool, bytes]] = {}


@cache
def _python_source_cached(path: str, source: bytes) -> tuple[tuple[str, ...], frozenset[str], bool, bytes]:
    names: list[str] = []
    strings: set[str] = set()
    relative = False
    tree = ast.parse(source.decode("utf-8"), filename=path)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            relative |= bool(node.level)
            mod = node.module or ""
            names += [mod] + [f"{mod}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and len(node.value) < 256:
            strings.add(node.value)
    digest = f"python{sys.version_info[0]}.{sys.version_info[1]}\0{ast.dump(_without_string_statements(tree))}".encode()
    return tuple(names), frozenset(strings), relative, digest


def _helper(name: str, local_dirs: tuple[Path, ...]) -> Path | None:
    """The helper file ``name`` (e.g. ``common.py``): in the first directory of
    ``local_dirs`` (the script's own) or, failing that, in exactly one of the others."""
    if name in _file_names(local_dirs[0], ".py"):
        return local_dirs[0] / name
    found = [d / name for d in local_dirs[1:] if name in _file_names(d, ".py")]
    if len(found) > 1:
        raise ValueError(f"helper {name!r} is ambiguous: {[str(f) for f in found]}")
    return found[0] if found else None


def _references(path: Path, local_dirs: tuple[Path, ...] | None, root: Path) -> tuple[set[str], set[Path]]:
    """(railradio modules, helper files) that ``path`` refers to.

    ``local_dirs``: for a workflow script, its directory and then the other script
    directories, whose ``*.py`` files are helpers (None for library modules, which import
    only ``railradio``)."""
    modules: set[str] = set()
    local: set[Path] = set()
    names, strings = _facts(path)
    if local_dirs is not None:  # a sibling script run by name (runpy)
        local |= {local_dirs[0] / v for v in strings & _file_names(local_dirs[0], ".py")}
    for n in names:
        if module_path(n, root) is not None:
            modules.add(n)
            modules.update(_parents(n))
        elif local_dirs is not None and "." not in n and (h := _helper(f"{n}.py", local_dirs)):
            local.add(h)
    return modules, local


@cache
def _listing(directory: Path) -> frozenset[str]:
    """The names of the files in ``directory`` (none if it is not a directory), listed once
    per process: a workflow's files do not come and go while its DAG is built (a process
    that adds or removes a module and hashes again calls :func:`clear_caches` first)."""
    if not directory.is_dir():
        return frozenset()
    return frozenset(p.name for p in directory.iterdir() if p.is_file())


def _file_names(directory: Path, suffix: str = "") -> frozenset[str]:
    return frozenset(n for n in _listing(directory) if n.endswith(suffix))


def clear_caches() -> None:
    """Forget the directory listings and module lookups (file contents are re-read anyway)."""
    _listing.cache_clear()
    _module_path.cache_clear()


def _data_files(path: Path, root: Path) -> set[Path]:
    data = root / "data"
    names = _file_names(data) if data.is_dir() else frozenset()
    return {data / v for v in _facts(path)[1] & names}


def script_closure(script: str | Path, root: Path = SRC_ROOT) -> dict[str, Path]:
    """Every file ``script`` runs or reads from this repository, by a stable name.

    Names: ``railradio.x.y`` for library modules, ``data/<file>`` for package data,
    ``local/<dir>/<file>.py`` for helper scripts (the script itself excluded: Snakemake
    tracks it). ``root``: the ``railradio`` package directory to resolve against.

    Parameters
    ----------
    script : str or pathlib.Path
        Path of the workflow script (e.g. ``workflow/scripts/fusion/point.py``); the other
        directories beside its directory are the other script directories.
    root : pathlib.Path, default SRC_ROOT
        The ``railradio`` package directory to resolve modules and package data against.

    Returns
    -------
    dict of str to pathlib.Path
        Stable name -> path of every file reached, sorted by name.

    Raises
    ------
    ValueError
        If ``script`` is not a file, a reached file uses a relative import, or a helper
        module is found in more than one other script directory.
    SyntaxError
        If a reached file is not valid Python.
    """
    script = Path(script).resolve()
    if not script.is_file():
        raise ValueError(f"script {str(script)!r} not found")
    others = sorted(d for d in script.parent.parent.iterdir() if d.is_dir() and d != script.parent)
    local_dirs = (script.parent, *others)
    out: dict[str, Path] = {}
    todo_local = [script]
    seen_local: set[Path] = set()
    modules: set[str] = set()
    while todo_local:  # the script and its sibling helpers
        f = todo_local.pop()
        if f in seen_local:
            continue
        seen_local.add(f)
        if f != script:
            out[f"local/{f.relative_to(script.parent.parent)}"] = f
        mods, local = _references(f, local_dirs, root)
        modules |= mods
        todo_local.extend(local - seen_local)
    todo = sorted(modules)
    seen: set[str] = set()
    while todo:  # the library, transitively
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        path = module_path(name, root)
        out[name] = path
        mods, _ = _references(path, None, root)
        todo.extend(mods - seen)
    for path in [script, *out.values()]:
        for d in _data_files(path, root):
            out[f"data/{d.name}"] = d
    return dict(sorted(out.items()))


def third_party(script: str | Path, root: Path = SRC_ROOT) -> dict[str, str]:
    """Installed distributions (name -> version) of the third-party packages that the
    script and the files of its closure import (``numpy``, ``scipy``, ``numba``, …).

    Parameters
    ----------
    script : str or pathlib.Path
        Path of the workflow script (e.g. ``workflow/scripts/fusion/point.py``); the other
        directories beside its directory are the other script directories.
    root : pathlib.Path, default SRC_ROOT
        The ``railradio`` package directory to resolve modules and package data against.

    Returns
    -------
    dict of str to str
        Distribution name -> installed version, sorted by name; standard-library modules
        have no distribution and do not appear.

    Raises
    ------
    ValueError
        As :func:`script_closure`.
    """
    return _third_party(script, script_closure(script, root))


def _third_party(script: str | Path, closure: dict[str, Path]) -> dict[str, str]:
    """:func:`third_party` of a script whose :func:`script_closure` is ``closure``."""
    files = [Path(script).resolve(), *(p for n, p in closure.items() if not n.startswith("data/"))]
    tops = {n.split(".")[0] for f in files for n in _facts(f)[0]} - {PACKAGE}
    dists = _distributions()
    out = {}
    for top in sorted(tops):
        for dist, ver in dists.get(top, ()):  # a standard-library module has none
            out[dist] = ver
    return dict(sorted(out.items()))


_STATEMENT_LISTS = ("body", "orelse", "finalbody")
"""The fields of a syntax-tree node that hold statements (``handlers`` and ``cases`` hold
nodes whose own ``body`` does)."""


def _is_string_statement(stmt: ast.stmt) -> bool:
    """Whether ``stmt`` is only a string constant (a docstring, an attribute note, any other
    bare string): evaluating it has no effect."""
    return isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Constant) and isinstance(stmt.value.value, str)


def _without_string_statements(tree: ast.AST) -> ast.AST:
    """``tree`` without its string-only statements, in place.

    Every statement that is only a string constant is removed from every statement list
    (module, class and function bodies, and the bodies of ``if``, ``for``, ``while``,
    ``with``, ``try``, ``match``): the docstrings, the attribute notes after assignments and
    any other bare string, none of which changes what runs. A body left empty becomes
    ``pass`` (so a function whose only statement is its docstring reads as ``pass``); a
    module may stay empty, and an ``else`` clause left empty is dropped, as if not written.

    Parameters
    ----------
    tree : ast.AST
        A parsed syntax tree; modified in place.

    Returns
    -------
    ast.AST
        ``tree``.
    """
    for node in ast.walk(tree):
        for field in _STATEMENT_LISTS:
            stmts = getattr(node, field, None)
            if not isinstance(stmts, list) or not stmts:  # an expression body (lambda, x if c else y) or none
                continue
            kept = [s for s in stmts if not _is_string_statement(s)]
            if len(kept) == len(stmts):
                continue
            if not kept and field != "orelse" and not isinstance(node, ast.Module):
                kept = [ast.Pass()]
            setattr(node, field, kept)
    return tree


def _smk_tokens(text: str) -> bytes:
    """A Snakemake rule file's tokens (type and text) without comments and blank lines."""
    skip = {tokenize.COMMENT, tokenize.NL}
    toks = tokenize.generate_tokens(io.StringIO(text).readline)
    return "\0".join(f"{t.type}:{t.string}" for t in toks if t.type not in skip).encode()


def file_digest(path: str | Path) -> bytes:
    """What of a file the code hashes hold, as bytes.

    Python source (``.py``): its syntax tree without docstrings and other string-only
    statements (attribute notes), printed by :func:`ast.dump` (no line numbers), after the
    Python minor version; so a comment, a docstring, an attribute note or a reformatting
    leaves it unchanged and any change of what runs changes it. A Snakemake rule
    file (``.smk``, ``Snakefile``): its tokens without comments and blank lines. Anything else
    (package data): its bytes.

    Parameters
    ----------
    path : str or pathlib.Path
        The file.

    Returns
    -------
    bytes
        The digestible form.

    Raises
    ------
    OSError
        If the file cannot be read.
    SyntaxError
        If a ``.py`` file is not valid Python.
    """
    path = Path(path)
    if path.suffix == ".py":
        return _python_source(path)[3]
    if path.suffix == ".smk" or path.name == "Snakefile":
        return _smk_tokens(path.read_text(encoding="utf-8"))
    return path.read_bytes()


@lru_cache(maxsize=1)
def _distributions() -> dict[str, tuple[tuple[str, str], ...]]:
    """Top-level import name -> ((distribution, version), ...) of the installed packages."""
    from importlib.metadata import packages_distributions, version

    return {top: tuple((d, version(d)) for d in sorted(set(ds))) for top, ds in packages_distributions().items()}


def script_code_hash(script: str | Path, root: Path = SRC_ROOT) -> str:
    """SHA-256 (16 hex digits) over the script's own code (Snakemake notices a changed
    script by its time stamp only), the names and code of :func:`script_closure` (each file
    as :func:`file_digest` reads it), and the versions of the third-party distributions
    they import (:func:`third_party`).

    Parameters
    ----------
    script : str or pathlib.Path
        Path of the workflow script (e.g. ``workflow/scripts/fusion/point.py``); the other
        directories beside its directory are the other script directories.
    root : pathlib.Path, default SRC_ROOT
        The ``railradio`` package directory to resolve modules and package data against.

    Returns
    -------
    str
        The first 16 hexadecimal digits of the SHA-256 digest.

    Raises
    ------
    OSError
        If ``script`` cannot be read (e.g. FileNotFoundError).
    ValueError
        As :func:`script_closure`.
    """
    h = hashlib.sha256()
    h.update(file_digest(script))
    closure = script_closure(script, root)
    for name, path in closure.items():
        h.update(name.encode())
        h.update(b"\0")
        h.update(file_digest(path))
        h.update(b"\0")
    for dist, ver in _third_party(script, closure).items():
        h.update(f"{dist}=={ver}\0".encode())
    return h.hexdigest()[:16]
