"""The code's shape: one concept per module (no module of src/ over 600 lines) and functions
short enough to read (no function of src/ or workflow/scripts/ over 80 lines, its docstring
not counted: a numpydoc section documents, it does not add logic)."""

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
