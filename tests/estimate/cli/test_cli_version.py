"""`slosh --version` names the installed package's version (new-user report defect 16)."""

import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

import pytest

from estimate.cli import main


def test_version_is_the_installed_packages(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"slosh-analogs {version('slosh-analogs')}"


def test_the_slosh_program_answers_version_without_a_command():
    slosh = Path(sys.executable).parent / "slosh"
    proc = subprocess.run([str(slosh), "--version"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and proc.stdout.startswith("slosh-analogs ")
