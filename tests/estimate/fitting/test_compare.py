"""`slosh compare`: the bundled example fitted with the estimated and the filtered input,
side by side; every difference and z checked against the two JSON records by hand."""

import json
import math
import re
from pathlib import Path

import pytest

from estimate.cli import main
from estimate.fitting.record import compare_fits, read_fit

ROOT = Path(__file__).resolve().parents[3]
A1 = str(ROOT / "examples" / "A1.toml")


@pytest.fixture(scope="module")
def fits(tmp_path_factory):
    folder = tmp_path_factory.mktemp("compare")
    a, b = folder / "A1_fit.json", folder / "A1_filtered.json"
    assert main(["fit", A1, "--model", "fixed,p1:nospring", "--json", str(a)]) == 0
    assert main(["fit", A1, "--model", "fixed,p1:nospring", "--input", "filtered",
                 "--json", str(b)]) == 0
    return folder, a, b


def _by_hand(a: dict, b: dict, name: str, derived: bool = False):
    """B - A, sqrt(se_a^2 + se_b^2) and their ratio, from the JSON records."""
    if derived:
        va, vb = a["derived"][name], b["derived"][name]
        sa, sb = a["derived_stderr"][name], b["derived_stderr"][name]
    else:
        va, vb = a["parameters"][name]["value"], b["parameters"][name]["value"]
        sa, sb = a["parameters"][name]["stderr"], b["parameters"][name]["stderr"]
    se = (sa**2 + sb**2) ** 0.5
    return vb - va, se, (vb - va) / se


def test_compare_prints_the_table_and_writes_what_the_records_give(fits, capsys):
    folder, a, b = fits
    out, png = folder / "cmp.json", folder / "cmp.png"
    capsys.readouterr()
    assert main(["compare", str(a), str(b), "--json", str(out), "--plot", str(png)]) == 0
    text = capsys.readouterr().out
    ja, jb = json.loads(a.read_text()), json.loads(b.read_text())
    doc = json.loads(out.read_text())
    names = ["fixed.mass", "p1.mass", "p1.length", "p1.damping"]
    assert list(doc["quantities"]) == names + ["p1.frequency_hz", "p1.damping_ratio"]
    for name in names + ["p1.frequency_hz", "p1.damping_ratio"]:
        derived = name.endswith(("_hz", "_ratio"))
        d, se, z = _by_hand(ja, jb, name, derived)
        got = doc["quantities"][name]["fits"]["A1_filtered"]
        assert got["difference"] == pytest.approx(d, rel=1e-12, abs=1e-300)
        assert got["combined_stderr"] == pytest.approx(se, rel=1e-12)
        assert got["z"] == pytest.approx(z, rel=1e-9)
        # the table's row: both values, both intervals, the difference and z
        row = next(line for line in text.splitlines() if line.split()[:1] == [name])
        assert f"{z:+.2f}" in row and f"{d:+.4g}" in row
        band = (jb["derived_interval_95"][name] if derived
                else jb["parameters"][name]["interval_95"])
        assert f"[{band[0]:.6g}, {band[1]:.6g}]" in row
    # the two fits of the same record: the z are on the low side, and the table says so
    assert "same data files (same SHA-256)" in text
    assert re.search(r"^z: the difference over the combined standard error", text, re.M)
    assert png.stat().st_size > 20_000


def test_the_plot_shows_each_interval_and_z(fits):
    _, a, b = fits
    fig = compare_fits([read_fit(a), read_fit(b)]).plot()
    shown = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_title() for ax in shown][:2] == ["fixed.mass [kg]", "p1.mass [kg]"]
    labels = [t.get_text() for t in shown[1].get_yticklabels()]
    z = compare_fits([read_fit(a), read_fit(b)]).quantity("p1.mass").difference(1)[2]
    assert labels == ["A1_fit", f"A1_filtered\nz = {z:+.2f}"]
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_a_fit_compared_with_itself_differs_by_zero(fits):
    _, a, _ = fits
    c = compare_fits([read_fit(a), read_fit(a)])
    for q in c.quantities:
        d, se, z = q.difference(1)
        assert d == 0 and (z == 0 or math.isnan(z))


def test_compare_needs_two_fits(fits, capsys):
    _, a, _ = fits
    assert main(["compare", str(a)]) == 2
    assert "at least two fit records" in capsys.readouterr().err
