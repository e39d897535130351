"""Every command of the README's "Command line" section runs as written on the bundled
examples, from a copy of the checkout's `examples/` in a temporary folder.

Each ```bash block of the section is one test, its commands run in order by the shell; the
first block (the fit the others read) runs once per test process. Blocks whose commands
take over ~30 s on the 2-core CI machine are marked slow (measured under load: diagnose 39 s,
montecarlo with an embedded Dask cluster 30 s, ntc 25-60 s cold; the others 2-12 s)."""

import os
import re
import shlex
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
SECTION = README[README.index("## Command line\n"):]
SECTION = SECTION[:SECTION.index("\n## ", 1)]
#: The ```bash blocks, one command a line; a ```python block right after a bash block runs
#: (as `python3 -c`) after that block's commands, in the same folder.
BLOCKS: list[list[str]] = []
for _kind, _code in re.findall(r"^ *```(bash|python)\n(.*?)^ *```", SECTION, flags=re.S | re.M):
    _code = textwrap.dedent(_code)
    if _kind == "bash":
        BLOCKS.append([line for line in _code.splitlines() if line.strip()])
    else:
        BLOCKS[-1].append(f"python3 -c {shlex.quote(_code)}")
#: Commands that take over ~30 s (see the module docstring).
SLOW = ("slosh diagnose", "slosh montecarlo", "slosh ntc")
QUICK_START = re.search(r"```bash\npython3 -m pip install \. && (slosh [^\n]*)\n```", README)


def _run(commands: list[str], cwd: Path) -> None:
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}",
               MPLBACKEND="Agg")
    for command in commands:
        proc = subprocess.run(command, shell=True, cwd=cwd, env=env, capture_output=True,
                              text=True, timeout=600)
        assert proc.returncode == 0, f"{command}\n{proc.stdout}\n{proc.stderr}"
        assert "Traceback" not in proc.stderr, proc.stderr


@pytest.fixture(scope="module")
def workspace(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("readme")
    shutil.copytree(ROOT / "examples", folder / "examples")
    _run(BLOCKS[0], folder)
    return folder


def test_the_section_is_what_the_tests_run():
    commands = [c for block in BLOCKS for c in block]
    assert commands[0].startswith("slosh fit examples/A1.toml --json A1_fit.json")
    for name in ("fit", "simulate", "tank", "diagnose", "export", "montecarlo", "ntc"):
        assert any(c.startswith(f"slosh {name} ") for c in commands), name
    assert any("--interface vehicle" in c for c in commands)
    # no runnable command hides in the prose: every inline `slosh <command> <file>` is run
    inline = re.findall(r"(?<!`)`(slosh [a-z]+ [a-z][^`]*)`", SECTION)
    assert all(c in commands for c in inline), inline


def test_the_quick_start_fit_runs_as_written(workspace):
    assert QUICK_START, "the quick start's `pip install . && slosh fit ...` line"
    _run([QUICK_START.group(1)], workspace)
    assert (workspace / "A1_fit.png").stat().st_size > 0


def _param(block: list[str]):
    marks = []
    if any(c.startswith(SLOW) for c in block):
        marks.append(pytest.mark.slow)
    needs_cc = any(c.startswith("make ") or "--fmu" in c for c in block)
    if needs_cc and not (shutil.which("cc") or shutil.which("gcc")) or \
            any(c.startswith("make ") for c in block) and not shutil.which("make"):
        marks.append(pytest.mark.skip(reason="needs a C compiler and make (README: Requirements)"))
    return pytest.param(block, marks=marks, id=block[0][:60])


@pytest.mark.parametrize("block", [_param(b) for b in BLOCKS[1:]])
def test_readme_command_line_block_runs(workspace, block):
    _run(block, workspace)
