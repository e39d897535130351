"""Every notebook in ``notebooks/`` runs from top to bottom (nbclient, a real kernel), shows
at least one figure inline, and is committed with the outputs it produces: a notebook whose
saved outputs are missing or stale fails.

Refresh the saved outputs with ``python tests/test_notebooks.py`` (executes every notebook
in place)."""

import math
import os
import re
import sys
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[1] / "notebooks").glob("*.ipynb"))
#: Text each notebook must print: a check that it did its job, not only that it ran.
EXPECT = {
    # since parameters at bounds are reported (issue 16) the hinge spring of A1 ends at 0
    "01_fit_lateral_test.ipynb": ["left out (at a bound): `p1.stiffness`"],
    "02_diagnose.ipynb": ["slosh_mode: ", "explains the data"],
    "03_export_and_montecarlo.ipynb": ["Monte Carlo: 200 draws"],
    "04_spinning_rig_and_ntc.ipynb": (["Nutation decays", "Nutation grows"]
                                      + ["NTC, linearised about steady spin"] * 4),
}
NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")
#: Saved and fresh numbers agree to 5 % (IPOPT and BLAS round differently from machine to
#: machine; a stale output differs by more, or in its text); numbers below 1e-9 in size are
#: round-off (relative errors of the C export) and compared as zero.
REL, TINY = 0.05, 1e-9
#: Lines with run times or rates ("0.52 s", "385 draws/s") are compared without their numbers.
TIMING = re.compile(r"\d s\b|/s\b")


def execute(path):
    nbformat = pytest.importorskip("nbformat", reason="needs nbformat (extra `test`)")
    nbclient = pytest.importorskip("nbclient", reason="needs nbclient (extra `test`)")
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(path.parent)}})
    # the kernel inherits the environment: a non-interactive MPLBACKEND (Agg, set for
    # scripts and CI) would stop the inline backend from showing the figures
    backend = os.environ.pop("MPLBACKEND", None)
    try:
        client.execute()
    finally:
        if backend is not None:
            os.environ["MPLBACKEND"] = backend
    return nb


def _text(output) -> str:
    if output.get("output_type") == "stream":
        return output.get("text", "")
    return output.get("data", {}).get("text/plain", "") if "image/png" not in output.get("data", {}) else ""


def _cell_outputs(cell):
    """(kinds, text) of a code cell's outputs; temporary paths and object ids masked.
    Consecutive stream outputs count as one: how the kernel splits printed text into
    stream messages depends on timing, not on what the cell printed."""
    kinds = []
    for o in cell.get("outputs", []):
        kind = "image" if "image/png" in o.get("data", {}) else o.get("output_type")
        if not (kind == "stream" and kinds and kinds[-1] == "stream"):
            kinds.append(kind)
    text = "".join(_text(o) for o in cell.get("outputs", []))
    text = re.sub(r"/tmp/\S+", "<tmp>", text)
    text = re.sub(r"0x[0-9a-f]+", "<id>", text)
    return kinds, text


def _numbers_agree(saved: str, fresh: str) -> bool:
    for a_line, b_line in zip(saved.splitlines(), fresh.splitlines()):
        if TIMING.search(a_line):
            continue
        for a, b in zip(NUMBER.findall(a_line), NUMBER.findall(b_line)):
            x, y = float(a), float(b)
            if max(abs(x), abs(y)) < TINY:
                continue
            if not math.isclose(x, y, rel_tol=REL, abs_tol=TINY):
                return False
    return True


def assert_outputs_current(saved_nb, fresh_nb, name):
    saved = [c for c in saved_nb.cells if c.cell_type == "code"]
    fresh = [c for c in fresh_nb.cells if c.cell_type == "code"]
    for i, (s, f) in enumerate(zip(saved, fresh)):
        assert s.source == f.source
        (sk, st), (fk, ft) = _cell_outputs(s), _cell_outputs(f)
        hint = f"{name}, code cell {i + 1}: saved outputs are stale; run `python tests/test_notebooks.py`"
        assert sk == fk, f"{hint} (saved {sk}, fresh {fk})"
        assert NUMBER.sub("#", st) == NUMBER.sub("#", ft), f"{hint}\n--- saved\n{st}\n--- fresh\n{ft}"
        assert _numbers_agree(st, ft), f"{hint}\n--- saved\n{st}\n--- fresh\n{ft}"


@pytest.mark.parametrize("path", [p for p in NOTEBOOKS if p.name in EXPECT], ids=lambda p: p.name)
def test_notebook_runs_shows_figures_and_is_saved_with_its_outputs(path):
    """Run with a real kernel; it must print what shows it did its job, display a figure
    inline, and match the outputs saved in the file."""
    nbformat = pytest.importorskip("nbformat", reason="needs nbformat (extra `test`)")
    saved = nbformat.read(path, as_version=4)
    assert any(c.get("outputs") for c in saved.cells if c.cell_type == "code"), \
        f"{path.name} is saved without outputs; run `python tests/test_notebooks.py`"
    nb = execute(path)
    text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code"
                   for o in c.get("outputs", []))
    for expected in set(EXPECT[path.name]):
        assert text.count(expected) >= EXPECT[path.name].count(expected), expected
    images = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
              if "image/png" in o.get("data", {})]
    assert images, f"{path.name} displays no figure inline"
    assert_outputs_current(saved, nb, path.name)


def test_stale_outputs_are_caught():
    """The comparison itself: a changed number or a missing figure is stale."""
    nbformat = pytest.importorskip("nbformat", reason="needs nbformat (extra `test`)")
    cell = nbformat.v4.new_code_cell("print(1)")
    cell.outputs = [nbformat.v4.new_output("stream", name="stdout", text="RMS residual 0.0624 N\nin 3.2 s\n")]
    saved = nbformat.v4.new_notebook(cells=[cell])
    same = nbformat.from_dict(saved)
    same.cells[0].outputs[0]["text"] = "RMS residual 0.0625 N\nin 9.9 s\n"
    assert_outputs_current(saved, same, "same")
    other = nbformat.from_dict(saved)
    other.cells[0].outputs[0]["text"] = "RMS residual 0.0900 N\nin 3.2 s\n"
    with pytest.raises(AssertionError, match="stale"):
        assert_outputs_current(saved, other, "other")
    figure = nbformat.from_dict(saved)
    figure.cells[0].outputs.append(nbformat.v4.new_output("display_data", data={"image/png": "AA=="}))
    with pytest.raises(AssertionError, match="stale"):
        assert_outputs_current(saved, figure, "figure")


if __name__ == "__main__":  # refresh the saved outputs
    import nbformat

    for p in NOTEBOOKS if len(sys.argv) < 2 else [Path(a).resolve() for a in sys.argv[1:]]:
        nbformat.write(execute(p), p)
        print("executed", p.name)
