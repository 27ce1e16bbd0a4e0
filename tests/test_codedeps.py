"""Code hashes derived from imports: every rule re-runs exactly when code its script runs
changes (railradio.codedeps), checked over every rule and every library module."""

from __future__ import annotations

import ast
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from railradio.codedeps import (
    _without_string_statements,
    clear_caches,
    file_digest,
    module_path,
    script_closure,
    script_code_hash,
)

from .conftest import ROOT, copy_workflow

SCRIPTS = sorted((ROOT / "workflow/scripts").glob("*/*.py"))
LIBRARY = sorted(p for p in (ROOT / "src/railradio").rglob("*.py") if "__pycache__" not in p.parts)


def rule_scripts() -> dict[str, Path]:
    """rule name -> script, read from the rule files (independently of Snakemake)."""
    out = {}
    for smk in sorted((ROOT / "workflow/rules").glob("*.smk")):
        text = smk.read_text()
        for m in re.finditer(r"^rule (\w+):\n(.*?)(?=^rule |\Z)", text, flags=re.M | re.S):
            s = re.search(r'^\s+script:\s*\n\s+"([^"]+)"', m.group(2), flags=re.M)
            if s:
                out[m.group(1)] = (smk.parent / s.group(1)).resolve()
    return out


def _dynamic_closure(scripts: list[Path]) -> dict[str, list[str]]:
    """What importing each script's imports really loads: in a child process per script
    (forked after the third-party packages are imported), the script's import statements
    (and its ``sys.path`` set-up) are executed and the railradio modules and helper files
    in ``sys.modules`` listed."""
    prog = r"""
import ast, json, os, sys
import numpy, scipy, xarray, numba, matplotlib, filterpy, pandas, h5netcdf  # noqa: F401
out = {}
for script in sys.argv[1:]:
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:
        try:
            os.close(r)
            here = os.path.dirname(script)
            top = os.path.dirname(here)
            sys.path.insert(0, here)
            before = set(sys.modules)
            tree = ast.parse(open(script).read())
            imports = [n for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))
                       or (isinstance(n, ast.Expr) and "sys.path" in ast.unparse(n))]
            exec(compile(ast.Module(body=imports, type_ignores=[]), script, "exec"), {"__file__": script})
            got = []
            for name, mod in sys.modules.items():
                f = getattr(mod, "__file__", None) or ""
                if name.startswith("railradio"):
                    got.append(name)
                elif name not in before and f and os.path.dirname(os.path.dirname(os.path.abspath(f))) == top:
                    got.append("local/" + os.path.relpath(os.path.abspath(f), top))
            os.write(w, json.dumps(sorted(got)).encode())
        except BaseException as exc:
            os.write(w, json.dumps({"error": repr(exc)}).encode())
        finally:
            os._exit(0)
    os.close(w)
    data = b""
    while chunk := os.read(r, 65536):
        data += chunk
    os.waitpid(pid, 0)
    out[script] = json.loads(data)
print(json.dumps(out))
"""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "MPLBACKEND": "Agg"}
    run = subprocess.run(
        [sys.executable, "-c", prog, *map(str, scripts)],
        env=env,
        capture_output=True,
        text=True,
        check=False,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    out = json.loads(run.stdout.splitlines()[-1])
    errors = {s: v["error"] for s, v in out.items() if isinstance(v, dict)}
    assert not errors, errors
    return out


def test_every_rule_has_a_script_and_every_script_a_rule_or_a_user():
    rules = rule_scripts()
    assert len(rules) >= 40
    assert all(p.is_file() for p in rules.values()), rules
    used = set(rules.values())
    for s in SCRIPTS:  # a script no rule names is a helper another script imports or runs
        if s not in used:
            assert any(f"local/{s.parent.name}/{s.name}" in script_closure(u) for u in used), s


def test_static_closure_contains_everything_the_imports_load():
    """The AST walk is conservative: each module or helper a script's imports really load
    is in its closure (a miss would leave a stale result)."""
    dynamic = _dynamic_closure(SCRIPTS)
    for s in SCRIPTS:
        static = set(script_closure(s))
        missing = set(dynamic[str(s)]) - static
        assert not missing, (s.name, sorted(missing))


def test_changing_a_module_changes_exactly_the_hashes_of_the_rules_that_run_it(tmp_path):
    """For every library module, helper script and data file: appending to it (a statement
    to Python) changes the code hash of exactly the rules whose script reaches it (and
    nothing else)."""
    src = tmp_path / "src"
    shutil.copytree(ROOT / "src/railradio", src / "railradio", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(ROOT / "workflow/scripts", tmp_path / "scripts")
    root = src / "railradio"
    rules = {r: tmp_path / "scripts" / p.relative_to(ROOT / "workflow/scripts") for r, p in rule_scripts().items()}
    closures = {r: script_closure(s, root) for r, s in rules.items()}
    base = {r: script_code_hash(s, root) for r, s in rules.items()}
    files = (
        sorted(root.rglob("*.py"))
        + sorted((root / "data").iterdir())
        + sorted(p for p in (tmp_path / "scripts").glob("*/*.py") if p not in rules.values())
    )
    reached = set()
    for f in files:
        original = f.read_bytes()
        f.write_bytes(original + (b"\n_edited = 1\n" if f.suffix == ".py" else b"\n"))
        try:
            changed = {r for r, s in rules.items() if script_code_hash(s, root) != base[r]}
        finally:
            f.write_bytes(original)
        expect = {r for r, c in closures.items() if f in c.values()}
        assert changed == expect, (str(f.relative_to(tmp_path)), sorted(changed ^ expect))
        reached |= changed
    assert reached == set(rules)  # every rule depends on some code
    assert {r: script_code_hash(s, root) for r, s in rules.items()} == base  # restored


def test_module_lookups_from_listings_match_the_file_system(tmp_path):
    """module_path answers from directory listings read once per process: the same answer as
    asking the file system for every module a rule reaches and for names that are not
    modules; a module added later is found after clear_caches()."""
    root = ROOT / "src/railradio"
    names = {n for s in rule_scripts().values() for n in script_closure(s) if not n.startswith(("data/", "local/"))}
    for n in sorted(names) + ["railradio.nr.no_such_module", "railradio.nr.tracking.ekf.run_ekf", "numpy.linalg"]:
        base = root.joinpath(*n.split(".")[1:])
        fs = base / "__init__.py" if (base / "__init__.py").is_file() else base.with_suffix(".py")
        assert module_path(n, root) == (fs if n.startswith("railradio") and fs.is_file() else None), n
    pkg = tmp_path / "railradio"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("", encoding="utf-8")
    assert module_path("railradio.late", pkg) is None
    (pkg / "late.py").write_text("X = 1\n", encoding="utf-8")
    clear_caches()
    assert module_path("railradio.late", pkg) == pkg / "late.py"


@pytest.mark.parametrize(
    ("module", "rules"),
    [  # modules each of these rules reaches only through another module or a helper script
        ("railradio.nr.study.keys", {"nr_figures", "nr_imm_figure"}),
        ("railradio.nr.tracking.bounds", {"nr_imm"}),
        ("railradio.plotting", {"nr_imm_key_numbers"}),
        ("railradio.nr.tracking.track", {"nr_case_track", "nr_case_calibrate", "nr_track", "nr_calibrate"}),
        ("railradio.nr.tracking.ekf", {"nr_case_track", "nr_case_calibrate", "nr_track", "nr_calibrate"}),
        ("railradio.nr.tracking.candidates", {"nr_case_track", "nr_case_calibrate", "nr_track", "nr_calibrate"}),
    ],
)
def test_known_dependencies_are_found(module, rules):
    scripts = rule_scripts()
    for r in rules:
        assert module in script_closure(scripts[r]), (module, r)


def test_a_plot_change_reruns_no_simulation():
    scripts = rule_scripts()
    for r in ("fusion_point", "nr_shard", "handover_shard", "tunnel_run", "chain_shard"):
        names = script_closure(scripts[r])
        assert not any(n.endswith(("figures", "plotting")) for n in names), (r, names)


def test_the_workflow_sets_each_rule_hash_from_its_script(tmp_path):
    """Every scripted rule of the loaded workflow carries ``code = script_code_hash(script)``
    (read from Snakemake's own rule objects after the Snakefile is parsed)."""
    wd = copy_workflow(tmp_path)
    # a wrapper at the copy's root: the workflow's root must not come from the main
    # Snakefile's directory (workflow.basedir), here the copy's root (common.smk: REPO_ROOT)
    (wd / "probe.smk").write_text(
        'include: "workflow/Snakefile"\n'
        "import json as _json\n"
        "print('PROBE' + _json.dumps({r.name: [getattr(r.params, 'code', None), r.script]"
        " for r in workflow.rules}))\n"
    )
    env = {**os.environ, "PYTHONPATH": str(wd / "src")}
    run = subprocess.run(
        [
            str(Path(sys.executable).parent / "snakemake"),
            "-s",
            "probe.smk",
            "-n",
            "-q",
            "rules",
            "--workflow-profile",
            "workflow/profiles/default",
            "all",
        ],
        cwd=wd,
        env=env,
        capture_output=True,
        text=True,
        check=False,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    line = next(x for x in run.stdout.splitlines() if x.startswith("PROBE"))
    loaded = json.loads(line[len("PROBE") :])
    assert set(loaded) >= set(rule_scripts())
    for name, (code, script) in loaded.items():
        if script is None:
            assert code is None, name
            continue
        path = (wd / "workflow/rules" / script).resolve()
        assert code == script_code_hash(path, wd / "src/railradio"), name
    assert not re.search(
        r"(?<!script_)code_hash\(", "".join(p.read_text() for p in (ROOT / "workflow/rules").glob("*.smk"))
    )


def test_a_data_file_named_by_the_script_itself_counts(tmp_path):
    scripts = tmp_path / "scripts" / "study"
    scripts.mkdir(parents=True)
    (scripts / "reader.py").write_text(
        "import json\nfrom importlib.resources import files\n"
        'json.loads((files("railradio") / "data" / "tdl.json").read_text())\n'
    )
    assert "data/tdl.json" in script_closure(scripts / "reader.py")
    a = script_code_hash(scripts / "reader.py")
    (scripts / "reader.py").write_text((scripts / "reader.py").read_text() + "edited = True\n")
    assert script_code_hash(scripts / "reader.py") != a  # the script's own code counts


def test_comments_docstrings_and_layout_change_no_hash_and_code_does(tmp_path):
    """The hashes hold what runs (file_digest): a comment, a docstring, any other string-only
    statement or a reformatting of a module or a rule file re-runs nothing; a changed
    constant, even inside an f-string or a rule's params, does."""
    mod = tmp_path / "m.py"
    mod.write_text('"""Module."""\n\ndef f(x):\n    """Doc."""\n    return x + 1  # one\n')
    base = file_digest(mod)
    for text in (
        '"""Another module text."""\n\ndef f(x):\n    """Numpydoc\n\n    Parameters\n    ----------\n    """\n'
        "    return x + 1\n",
        "def f(x):\n    # a comment\n    return (x +\n            1)\n",
    ):
        mod.write_text(text)
        assert file_digest(mod) == base, text
    mod.write_text('def f(x):\n    """Doc."""\n    return x + 2\n')
    assert file_digest(mod) != base
    mod.write_text("def f(x):\n    y = x\n    return y\n")
    later = file_digest(mod)
    mod.write_text('def f(x):\n    y = x\n    "a string statement"\n    return y\n')
    assert file_digest(mod) == later  # a string statement anywhere changes nothing that runs
    mod.write_text('def f(x):\n    y = x\n    f"{y}"\n    return y\n')
    assert file_digest(mod) != later  # an f-string is evaluated: it stays
    rules = tmp_path / "r.smk"
    rules.write_text('rule a:  # first\n    params:\n        k=f"{1}"\n    shell: "true"\n')
    base = file_digest(rules)
    rules.write_text('# header\n\nrule a:\n    params:\n        k=f"{1}"  # why\n    shell: "true"\n')
    assert file_digest(rules) == base
    rules.write_text('rule a:\n    params:\n        k=f"{2}"\n    shell: "true"\n')
    assert file_digest(rules) != base
    data = tmp_path / "t.json"
    data.write_text('{"a": 1}')
    first = file_digest(data)
    data.write_text('{"a": 1} ')
    assert file_digest(data) != first  # data: its bytes


def test_attribute_notes_change_no_hash_and_assigned_values_do(tmp_path):
    """An attribute note (a string statement after an assignment), at module level, in a
    class body or in a nested body, is not hashed: rewording it re-runs nothing; changing an
    assigned value does. A body left with only strings reads as ``pass`` and stays valid."""

    def source(note: str, limit: int = 1, x: int = 1, last: str = '    """Only a docstring."""') -> str:
        return (
            '"""Module."""\n\n'
            f"LIMIT = {limit}\n"
            f'"""{note} (module)."""\n\n\n'
            "class C:\n"
            '    """Class."""\n\n'
            f"    x: int = {x}\n"
            f'    """{note} (class)."""\n'
            "    if LIMIT:\n"
            "        y = 2\n"
            f'        """{note} (nested)."""\n'
            "    else:\n"
            f'        """{note} (an else of notes only)."""\n'
            "    while False:\n"
            f'        """{note} (a loop body of notes only)."""\n\n\n'
            f"def f():\n{last}\n"
        )

    mod = tmp_path / "m.py"
    mod.write_text(source("The limit"))
    base = file_digest(mod)
    for same in (source("Another, longer wording of the note"), source("The limit", last="    pass")):
        mod.write_text(same)
        assert file_digest(mod) == base, same
    for changed in (source("The limit", limit=2), source("The limit", x=2), source("The limit", last="    return")):
        mod.write_text(changed)
        assert file_digest(mod) != base, changed
    tree = _without_string_statements(ast.parse(source("The limit")))
    compile(ast.fix_missing_locations(tree), str(mod), "exec")  # the emptied bodies hold a pass


def test_third_party_versions_enter_exactly_the_hashes_of_the_rules_that_import_them(monkeypatch):
    import railradio.codedeps as cd

    rules = rule_scripts()
    shard, figure = rules["nr_shard"], rules["fusion_figure"]
    base = {s: script_code_hash(s) for s in (shard, figure)}
    real = cd._distributions()

    def bumped(top):
        return {**real, top: tuple((d, v + ".post1") for d, v in real[top])}

    monkeypatch.setattr(cd, "_distributions", lambda: bumped("numba"))
    assert script_code_hash(shard) != base[shard] and script_code_hash(figure) == base[figure]
    monkeypatch.setattr(cd, "_distributions", lambda: bumped("matplotlib"))
    assert script_code_hash(shard) == base[shard] and script_code_hash(figure) != base[figure]
