"""Every ``slosh`` command refuses to replace an existing output file unless given
``--overwrite``: the exit status is 2, the error names the file, and its bytes are kept."""

from pathlib import Path

import pytest

from estimate.cli import main

ROOT = Path(__file__).resolve().parents[3]
A1 = str(ROOT / "examples" / "A1.toml")
SPACECRAFT = str(ROOT / "examples" / "spacecraft.toml")
KEEP = b"earlier result, not to be lost\n"


def _commands(tmp: Path) -> dict[str, tuple[list[str], Path]]:
    """Command line and the existing output it must keep."""
    out = tmp / "out.json"
    return {
        "simulate": (["simulate", A1, "--params", str(tmp / "p.json"), "--out",
                      str(tmp / "sim.csv")], tmp / "sim.csv"),
        "fit": (["fit", A1, "--json", str(out)], out),
        "fit-plot": (["fit", A1, "--plot", str(tmp / "fit.png")], tmp / "fit.png"),
        "diagnose": (["diagnose", A1, "--json", str(out)], out),
        "montecarlo": (["montecarlo", str(tmp / "fit.json"), A1, "--samples", "2", "--local",
                        "--out", str(tmp)], tmp / "montecarlo.json"),
        "tank": (["tank", "--shape", "sphere", "--radius", "0.1", "--fill", "0.5",
                  "--json", str(out)], out),
        "tank-plot": (["tank", "--shape", "sphere", "--radius", "0.1", "--fill", "0.5",
                       "--plot", str(tmp / "tank.png")], tmp / "tank.png"),
        "ntc": (["ntc", SPACECRAFT, "--json", str(out)], out),
    }


@pytest.mark.parametrize("name", ["simulate", "fit", "fit-plot", "diagnose", "montecarlo",
                                  "tank", "tank-plot", "ntc"])
def test_existing_output_is_kept_without_overwrite(name, tmp_path, capsys):
    argv, target = _commands(tmp_path)[name]
    target.write_bytes(KEEP)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert str(target) in err and "--overwrite" in err
    assert target.read_bytes() == KEEP


def test_tank_overwrite_replaces_the_json(tmp_path):
    out = tmp_path / "t.json"
    out.write_bytes(KEEP)
    assert main(["tank", "--shape", "sphere", "--radius", "0.1", "--fill", "0.5",
                 "--json", str(out), "--overwrite"]) == 0
    assert out.read_bytes() != KEEP and b'"modes"' in out.read_bytes()
