"""The code's shape: one concept per module (no module of src/ over 600 lines), functions
short enough to read (no function of src/ or workflow/scripts/ over 80 lines, its docstring
not counted: a numpydoc section documents, it does not add logic), and the nr package in
layers with no import cycle and no class over 300 lines."""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MAX_MODULE_LINES = 600
MAX_FUNCTION_LINES = 80


def _python_files(*dirs: str) -> list[Path]:
    return sorted(p for d in dirs for p in (ROOT / d).rglob("*.py"))


def _code_lines(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    n = node.end_lineno - node.lineno + 1
    first = node.body[0]
    if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(first.value.value, str):
        n -= first.end_lineno - first.lineno + 1
    return n


def test_no_module_over_600_lines():
    long = {
        str(p.relative_to(ROOT)): n
        for p in _python_files("src")
        if (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES
    }
    assert not long, f"modules over {MAX_MODULE_LINES} lines: {long}"


def test_no_function_over_80_lines():
    long = []
    for p in _python_files("src", "workflow/scripts"):
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and _code_lines(node) > MAX_FUNCTION_LINES:
                long.append(f"{p.relative_to(ROOT)}:{node.name} ({_code_lines(node)})")
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines: {long}"


def test_the_counter_counts(tmp_path):
    """The limit can fail: a function of 81 lines (its def and 80 statements) is caught, its
    docstring aside."""
    src = 'def f():\n    """doc\n\n    more\n    """\n' + "    x = 1\n" * 80
    node = ast.parse(src).body[0]
    assert _code_lines(node) == 81 > MAX_FUNCTION_LINES


# The nr package in layers (like Sionna's phy/): each layer imports only the layers below it.
NR = ROOT / "src" / "railradio" / "nr"
NR_LAYERS = {
    "waveform": set(),
    "channel": {"waveform"},
    "receiver": {"waveform", "channel"},
    "synthesis": {"waveform", "channel", "receiver"},
    "tracking": {"waveform", "channel"},
    "engine": {"waveform", "channel", "receiver", "synthesis", "tracking"},
    "study": {"waveform", "channel", "receiver", "synthesis", "tracking", "engine"},
}
MAX_NR_CLASS_LINES = 300


def _nr_imports() -> dict[str, set[str]]:
    """{module: the railradio.nr modules and packages it imports} for every nr module."""
    out = {}
    for p in _python_files("src/railradio/nr"):
        name = ".".join(p.relative_to(ROOT / "src").with_suffix("").parts).removesuffix(".__init__")
        deps = set()
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("railradio.nr"):
                deps |= {node.module} | {f"{node.module}.{a.name}" for a in node.names}
            elif isinstance(node, ast.Import):
                deps |= {a.name for a in node.names if a.name.startswith("railradio.nr")}
        out[name] = deps
    return {m: {d for d in deps if d in out and d != m} for m, deps in out.items()}


def _layer(module: str) -> str:
    parts = module.split(".")
    return parts[2] if len(parts) > 2 else ""


def test_nr_is_in_layers():
    """src/railradio/nr holds only its layers, and each module imports its own layer and the
    layers below it."""
    top = {p.name for p in NR.iterdir() if p.name != "__pycache__"}
    assert top == {"__init__.py"} | set(NR_LAYERS), top - ({"__init__.py"} | set(NR_LAYERS))
    wrong = [
        f"{m} -> {d}"
        for m, deps in _nr_imports().items()
        for d in deps
        if _layer(m) and _layer(d) != _layer(m) and _layer(d) not in NR_LAYERS[_layer(m)]
    ]
    assert not wrong, wrong


def test_no_nr_import_cycle():
    """The nr modules' import graph is acyclic (a module importing its own package's
    ``__init__`` counts as an edge, so ``from railradio.nr.x import y`` inside layer x fails)."""
    graph = _nr_imports()
    state: dict[str, int] = {}
    cycles = []

    def visit(u: str, path: list[str]) -> None:
        state[u] = 1
        for v in sorted(graph[u]):
            if state.get(v) == 1:
                cycles.append(path[path.index(v) :] + [v])
            elif v not in state:
                visit(v, path + [v])
        state[u] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m, [m])
    assert not cycles, cycles


def test_no_nr_class_over_300_lines():
    long = [
        f"{p.relative_to(ROOT)}:{node.name} ({node.end_lineno - node.lineno + 1})"
        for p in _python_files("src/railradio/nr")
        for node in ast.walk(ast.parse(p.read_text()))
        if isinstance(node, ast.ClassDef) and node.end_lineno - node.lineno + 1 > MAX_NR_CLASS_LINES
    ]
    assert not long, f"nr classes over {MAX_NR_CLASS_LINES} lines: {long}"


def test_snakemake_alone_finds_the_workflow_and_its_default_profile(monkeypatch):
    """Snakemake's standard layout: from the repository root, ``snakemake`` with neither
    ``-s`` nor ``--workflow-profile`` reads workflow/Snakefile and the profile
    workflow/profiles/default (make and the docs rely on it). Only the command line is
    parsed: no workflow is loaded."""
    from snakemake.cli import parse_args, resolve_snakefile

    monkeypatch.chdir(ROOT)
    _, args = parse_args(["-n"])
    assert resolve_snakefile(args.snakefile, allow_missing=True) == Path("workflow/Snakefile")
    assert not (ROOT / "Snakefile").exists()  # it would be found first
    assert args.cores == 2 and args.scheduler == "greedy"  # workflow/profiles/default
