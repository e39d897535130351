"""Notebook 04 (spinning rig, spacecraft NTC) runs from top to bottom."""

from pathlib import Path

import pytest

NOTEBOOK = Path(__file__).resolve().parents[1] / "notebooks" / "04_spinning_rig_and_ntc.ipynb"


def test_notebook_04_runs():
    nbformat = pytest.importorskip("nbformat", reason="needs nbformat (extra `test`)")
    nbclient = pytest.importorskip("nbclient", reason="needs nbclient (extra `test`)")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                                     resources={"metadata": {"path": str(NOTEBOOK.parent)}})
    client.execute()
    text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code"
                   for o in c.get("outputs", []))
    assert "Nutation decays" in text and "Nutation grows" in text
    assert text.count("NTC, linearised about steady spin") == 4
