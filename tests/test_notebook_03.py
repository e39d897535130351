"""Notebook 03 (export, vehicle coupling, Monte Carlo) runs from top to bottom."""

from pathlib import Path

import pytest

NOTEBOOK = Path(__file__).resolve().parents[1] / "notebooks" / "03_export_and_montecarlo.ipynb"


def test_notebook_03_runs():
    nbformat = pytest.importorskip("nbformat", reason="needs nbformat (extra `test`)")
    nbclient = pytest.importorskip("nbclient", reason="needs nbclient (extra `test`)")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                                     resources={"metadata": {"path": str(NOTEBOOK.parent)}})
    client.execute()
    text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code"
                   for o in c.get("outputs", []))
    assert "Monte Carlo: 200 draws" in text
