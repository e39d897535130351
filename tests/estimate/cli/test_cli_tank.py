"""`slosh tank` subcommand and `TankPrediction.analog()`."""

import argparse
import json
import math

import pytest

from analogs.tank import Sphere, predict
from estimate.cli import main
from estimate.cli import tank as _cli_tank


def parse(argv):
    ap = argparse.ArgumentParser(prog="slosh")
    _cli_tank.add_parser(ap.add_subparsers())
    return ap.parse_args(argv)


def test_cli_json_and_table(tmp_path, capsys):
    out = tmp_path / "t.json"
    args = parse(["tank", "--shape", "sphere", "--radius", "0.1016", "--fill", "0.6",
                  "--viscosity", "0.893e-6", "--json", str(out)])
    assert args.run(args) == 0
    text = capsys.readouterr().out
    assert "mode" in text and "fixed mass" in text
    doc = json.loads(out.read_text())
    assert doc["shape"] == "sphere" and len(doc["modes"]) == 2
    assert doc["modes"][0]["damping_ratio"] == pytest.approx(0.00703, abs=1e-5)


def test_cli_volume_fill_legacy_and_plot(tmp_path):
    pytest.importorskip("matplotlib")
    png = tmp_path / "t.png"
    args = parse(["tank", "--radius", "0.1016", "--volume-fill", "0.648", "--method", "legacy",
                  "--plot", str(png)])
    assert args.run(args) == 0
    assert png.stat().st_size > 10_000
    # what the plot shows: units, the requested fill marked, the legacy range shaded
    from plot_checks import assert_units

    pred = predict(Sphere(0.1016), volume_fill=0.648, method="legacy")
    fig = _cli_tank._plot(args, Sphere(0.1016), pred.liquid, str(tmp_path / "again.png"), pred)
    mass, freq, damping = fig.axes[:3]
    for ax in (mass, freq, damping):
        assert_units(ax, x=ax is damping)
        assert [ln.get_xdata()[0] for ln in ax.get_lines() if ln.get_gid() == "requested fill"] \
            == [pytest.approx(100 * pred.fill_fraction)]
    legacy = [p for p in freq.patches if p.get_label() == "legacy basis not converged"]
    assert legacy and legacy[0].get_x() == pytest.approx(50.0)
    assert any("validity" in p.get_label() or "correlation" in p.get_label() for p in damping.patches)
    assert mass.child_axes[0].get_xlabel() == "fill [% of tank volume]"


def test_the_frequency_labels_sit_beside_their_curves(tmp_path):
    """A cylinder's mode frequencies are level with the fill above half full: a label level
    with the requested fill's point lay on the curve. Each mode's label stays inside the
    panel and off every curve."""
    pytest.importorskip("matplotlib")
    import numpy as np
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from analogs.tank import Cylinder

    args = parse(["tank", "--shape", "cylinder", "--radius", "0.1016", "--length", "0.3",
                  "--fill", "0.6", "--plot", str(tmp_path / "c.png")])
    tank = Cylinder(0.1016, 0.3)
    pred = predict(tank, fill=0.6)
    fig = _cli_tank._plot(args, tank, pred.liquid, str(tmp_path / "c.png"), pred)
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    freq = fig.axes[1]
    labels = [t for t in freq.texts if t.get_gid() == "requested fill label"]
    assert [t.get_text() for t in labels] == [f"{m.frequency_hz:.3g} Hz" for m in pred.modes]
    curves = [ln for ln in freq.get_lines() if ln.get_label().startswith("mode")]
    assert len(curves) == len(pred.modes)
    for text in labels:
        box = text.get_window_extent(renderer)
        assert freq.get_window_extent(renderer).contains(box.x0, box.y0)
        assert freq.get_window_extent(renderer).contains(box.x1, box.y1)
        for ln in curves:
            x, y = (np.asarray(v, float) for v in ln.get_data())
            fine = np.linspace(x[0], x[-1], 2000)  # the drawn segments, densely
            px, py = freq.transData.transform(np.column_stack([fine, np.interp(fine, x, y)])).T
            assert not np.any((px >= box.x0) & (px <= box.x1) & (py >= box.y0) & (py <= box.y1)), \
                (text.get_text(), ln.get_label())


def test_cli_bad_input_exits_2_with_message(capsys):
    assert main(["tank", "--shape", "cylinder", "--radius", "0.1", "--fill", "0.5"]) == 2
    assert "--shape cylinder takes `--radius`, `--length` (m); got none for `--length`" \
        in capsys.readouterr().err
    assert main(["tank", "--shape", "sphere", "--radius", "0.1", "--width", "0.2",
                 "--fill", "0.5"]) == 2
    assert "`--width` does not apply" in capsys.readouterr().err
    assert main(["tank", "--radius", "-1", "--fill", "0.5"]) == 2
    assert "--radius -1: expected 1e-06 to 1000 m" in capsys.readouterr().err
    assert main(["tank", "--shape", "rectangular", "--length", "0.3", "--width", "1e300",
                 "--height", "0.2", "--fill", "0.5"]) == 2
    assert "--width 1e+300: expected 1e-06 to 1000 m" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        parse(["tank", "--shape", "cube", "--radius", "1", "--fill", "0.5"])


def test_analog_model_uses_prediction():
    p = predict(Sphere(0.1016), fill=0.6)
    model = p.analog()
    text = repr(model)
    assert "FixedMass('fixed'" in text and "Pendulum('p2'" in text
    m = p.modes[0]
    c = 2 * m.damping_ratio * m.mass * m.length**2 * 2 * math.pi * m.frequency_hz
    got = float(text.split("HingeDamper('p1', damping=")[1].split(")")[0])
    assert got == pytest.approx(c, rel=1e-12)  # round-off of omega only


def test_rectangular_tank_in_closed_form(tmp_path, capsys):
    """SP-106 / Ibrahim: ``omega^2 = (pi g / a) tanh(pi h / a)`` for a box of length a along
    the motion filled to depth h."""
    import json

    out = tmp_path / "box.json"
    assert main(["tank", "--shape", "rectangular", "--length", "0.4", "--width", "0.2",
                 "--height", "0.3", "--fill", "0.5", "--gravity", "9.81", "--json",
                 str(out)]) == 0
    data = json.loads(out.read_text())
    h = 0.15
    f1 = math.sqrt(math.pi * 9.81 / 0.4 * math.tanh(math.pi * h / 0.4)) / (2 * math.pi)
    assert data["modes"][0]["frequency_hz"] == pytest.approx(f1, rel=1e-12)
    assert data["liquid_mass"] == pytest.approx(998.2 * 0.4 * 0.2 * h, rel=1e-12)
    assert "closed form" in capsys.readouterr().out


def test_the_second_mode_says_its_damping_is_the_first_modes(tmp_path, capsys):
    """New-user report defect 20: mode 2 got mode 1's damping ratio in silence."""
    out = tmp_path / "t.json"
    args = parse(["tank", "--radius", "0.1016", "--fill", "0.6", "--json", str(out)])
    assert args.run(args) == 0
    text = capsys.readouterr().out
    row2 = next(line for line in text.splitlines() if line.split()[:1] == ["2"])
    assert row2.endswith(" *")
    assert "* the first mode's value (see the note below)" in text
    assert "wave/bob: wave height at the wall over the bob's lateral amplitude" in text
    doc = json.loads(out.read_text())
    assert doc["modes"][1]["damping_ratio"] == doc["modes"][0]["damping_ratio"]
    assert any(n.startswith("modes 2 and up: the first mode's damping ratio") for n in doc["notes"])
    # one mode: nothing to say
    args = parse(["tank", "--radius", "0.1016", "--fill", "0.6", "--modes", "1"])
    assert args.run(args) == 0
    assert "first mode's" not in capsys.readouterr().out
