"""The tutorial notebook (docs/tutorial.ipynb) runs as committed: every cell executes without
an error in a fresh kernel of the project's environment (nbclient; the kernel talks over IPC
sockets, no network port), and it is committed without outputs, so none can go stale."""

from __future__ import annotations

import pytest

from .conftest import ROOT

NOTEBOOK = ROOT / "docs/tutorial.ipynb"


def test_tutorial_is_committed_without_outputs():
    nbformat = pytest.importorskip("nbformat")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code and all(not c.outputs and c.execution_count is None for c in code)


@pytest.mark.slow
def test_tutorial_executes(tmp_path):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    from jupyter_client.manager import KernelManager

    nb = nbformat.read(NOTEBOOK, as_version=4)
    km = KernelManager(kernel_name="python3", transport="ipc", connection_file=str(tmp_path / "kernel.json"))
    km.ip = str(tmp_path / "kernel-ipc")  # the sockets' path prefix (default: in the working directory)
    nbclient.NotebookClient(nb, km=km, timeout=600, resources={"metadata": {"path": str(NOTEBOOK.parent)}}).execute()
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.get("output_type") == "error"]
    assert not errors, errors
    text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.outputs)
    assert "beside a source value" in text and "train at x =" in text
