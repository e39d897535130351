"""The command line prints a user's error as one line and lets a defect show its traceback."""

from pathlib import Path

import pytest

from analogs import InputError
from estimate.cli import fit as cli_fit
from estimate.cli import main

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"


def test_an_input_error_is_one_line_with_status_2(capsys):
    assert main(["fit", str(EXAMPLES / "A1.toml"), "--model", "fixed,q1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("slosh fit: error: --model 'fixed,q1'") and err.count("\n") == 1


def test_an_os_error_names_the_file(capsys, tmp_path):
    folder = tmp_path / "a_folder.json"
    folder.mkdir()
    # the output is a folder: refused before the fit with the path in the message
    status = main(["fit", str(EXAMPLES / "A1.toml"), "--json", str(folder), "--overwrite"])
    assert status == 2
    assert str(folder) in capsys.readouterr().err


def test_a_programming_error_is_not_disguised_as_a_user_error(monkeypatch):
    """Before, every ValueError/KeyError became `error: ...` with status 2, hiding defects."""
    def broken(args):
        raise KeyError("internal table lookup")

    monkeypatch.setattr(cli_fit, "run", broken)
    with pytest.raises(KeyError, match="internal table lookup"):
        main(["fit", str(EXAMPLES / "A1.toml")])


def test_input_error_is_a_value_error_for_library_users():
    assert issubclass(InputError, ValueError)


def test_a_file_left_open_by_an_interrupted_import_is_not_a_warning_line(monkeypatch, capsys):
    """A SIGINT while Python reads a module's bytecode leaves that file to the garbage
    collector; its ResourceWarning is the interpreter's, and the interrupt's message must stay
    the command's one line (seen on a loaded machine: 'warning: unclosed file <...pyc>')."""
    import warnings

    def leaky(args):
        warnings.warn("unclosed file <_io.BufferedReader name='x.pyc'>", ResourceWarning, stacklevel=2)
        warnings.warn("a user's warning", UserWarning, stacklevel=2)
        return 0

    monkeypatch.setattr(cli_fit, "run", leaky)
    assert main(["fit", str(EXAMPLES / "A1.toml")]) == 0
    assert capsys.readouterr().err == "warning: a user's warning\n"


def test_a_refused_case_file_does_not_load_the_fits_libraries(tmp_path):
    """Loading and checking a case is NumPy's work; SciPy's signal, stats, optimize and
    interpolate packages (1.5-2 s to import on a 2-core machine) load only when the fit runs,
    so a typo in a case file is answered at once."""
    import subprocess
    import sys

    toml = (EXAMPLES / "A1.toml").read_text().replace("dry_mass = 1.2", "dry_mass = 1e30")
    (tmp_path / "bad.toml").write_text(toml)
    (tmp_path / "A1.csv").write_bytes((EXAMPLES / "A1.csv").read_bytes())
    code = ("import sys\nfrom estimate.cli import main\nstatus = main(['fit', 'bad.toml'])\n"
            "heavy = [m for m in ('scipy.signal', 'scipy.stats', 'scipy.optimize', "
            "'scipy.interpolate') if m in sys.modules]\nprint(status, heavy)\n")
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120)
    assert "[rig] dry_mass: expected" in proc.stderr, proc.stderr
    assert proc.stdout.strip() == "2 []", proc.stdout
