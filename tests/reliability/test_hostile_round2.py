"""Issue 26: the bad and weak attempts of the second hostile-input round, rerun one per row.

Every row runs the ``slosh`` command line in a new process with a timeout (a hang is a
failure: :data:`TIMEOUT`) on inputs built in a fresh folder from the bundled examples, and
checks the new behaviour: the exit status, the one line that names the file, key or
option, and what was (not) written. Bad finding 1 (a planted native library) is in
``test_planted_library.py``.

Campaign rows replace the fit of a task by a stub (a fixed valid outcome, set up in the
child process before the command runs): what they test is the store and the runner, and a
real fit would only cost time. The stub estimates one parameter, ``stub.value`` =
:data:`STUB_MASS` (not a quantity the report plots: no figure is drawn).
"""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
CAMPAIGN = EXAMPLES / "campaign"
#: Seconds a row may take: every command here answers in a few seconds (imports included,
#: on a loaded 2-core machine); one that blocks on a pipe or reads /dev/zero never does.
TIMEOUT = 120
STUB_MASS = 1.5

pytestmark = pytest.mark.skipif(os.name != "posix", reason="FIFOs and devices")


def slosh(argv: list[str], cwd: Path, *, prelude: str = "", env: dict | None = None,
          timeout: float = TIMEOUT) -> subprocess.CompletedProcess:
    """``slosh ARGV`` in a new process (after running ``prelude``), with a timeout."""
    code = textwrap.dedent(prelude) + ("\nimport sys\nfrom estimate.cli import main\n"
                                       f"sys.exit(main({[str(a) for a in argv]!r}))\n")
    full = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1",
            "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "MPLBACKEND": "Agg",
            **(env or {})}
    try:
        return subprocess.run([sys.executable, "-c", code], cwd=cwd, env=full,
                              capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        pytest.fail(f"slosh {' '.join(map(str, argv))} did not end within {timeout} s (a hang)")


def _error(proc: subprocess.CompletedProcess, status: int = 2) -> str:
    """The one-line error of a refused command."""
    assert proc.returncode == status, proc.stderr
    assert "Traceback" not in proc.stderr, proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if "error:" in ln]
    assert len(lines) == 1, proc.stderr
    return lines[0]


def _a1(d: Path, name: str = "A1", *, toml=lambda s: s, csv_text=None) -> Path:
    text = (EXAMPLES / "A1.toml").read_text().replace('"A1.csv"', f'"{name}.csv"')
    (d / f"{name}.toml").write_text(toml(text))
    (d / f"{name}.csv").write_text(csv_text if csv_text is not None
                                   else (EXAMPLES / "A1.csv").read_text())
    return d / f"{name}.toml"


def _params(d: Path) -> Path:
    (d / "p.json").write_bytes((EXAMPLES / "A1_params.json").read_bytes())
    return d / "p.json"


def _fit_file(d: Path, **changes) -> Path:
    values = json.loads((EXAMPLES / "A1_params.json").read_text())
    data = {"model_spec": "fixed,p1", "case": "A1", "converged": True, "r_squared": 0.99,
            "status": "Solve_Succeeded",
            "parameters": {n: {"value": v, "unit": "", "estimated": True} for n, v in values.items()},
            "covariance": {"parameters": ["fixed.mass"], "matrix": [[1e-6]]}} | changes
    (d / "fit.json").write_text(json.dumps(data))
    return d / "fit.json"


def _fifo(d: Path, name: str = "pipe") -> Path:
    os.mkfifo(d / name)
    return d / name


ROWS: dict[str, Callable[[Path], None]] = {}
#: rows run by ``pytest -m slow`` only
SLOW: set[str] = set()


def row(name: str, *, slow: bool = False):
    def register(fn):
        ROWS[name] = fn
        if slow:
            SLOW.add(name)
        return fn
    return register


# -- bad 2: special files hang or exhaust memory ---------------------------------------------


@row("bad 2: montecarlo with a FIFO as the fit file is refused, not blocked on")
def _(d):
    line = _error(slosh(["montecarlo", _fifo(d), _a1(d), "--samples", "2", "--local",
                         "--out", d / "mc"], d))
    assert "pipe: expected a fit file (JSON), found a named pipe (FIFO)" in line


@row("bad 2: simulate --params FIFO is refused, not blocked on")
def _(d):
    line = _error(slosh(["simulate", _a1(d), "--params", _fifo(d), "--out", d / "s.csv"], d))
    assert "found a named pipe (FIFO)" in line and not (d / "s.csv").exists()


@row("bad 2: simulate --params /dev/zero is refused before reading")
def _(d):
    line = _error(slosh(["simulate", _a1(d), "--params", "/dev/zero", "--out", d / "s.csv"], d),)
    assert "/dev/zero: expected a parameter file (JSON), found a character device" in line


@row("bad 2: a case whose data is a FIFO: the campaign does not hang in discovery")
def _(d):
    folder = _campaign(d)
    toml = folder / "F40_sine_3mm.toml"
    toml.write_text(toml.read_text().replace('data = "F40_sine_3mm.csv"', 'data = "pipe"'))
    _fifo(folder)
    proc = slosh(["campaign", folder, "--out", d / "out", "--threads", "1"], d, prelude=_STUB)
    assert proc.returncode == 1, proc.stderr
    rows = _table(d / "out")
    assert "found a named pipe (FIFO)" in rows["F40_sine_3mm"]["error"]
    assert rows["F40_sine_1.5mm"]["status"] == "ok"


@row("bad 2: a case whose data is /dev/zero: the campaign does not hash it forever")
def _(d):
    folder = _campaign(d)
    toml = folder / "F40_sine_3mm.toml"
    toml.write_text(toml.read_text().replace('data = "F40_sine_3mm.csv"', 'data = "/dev/zero"'))
    proc = slosh(["campaign", folder, "--out", d / "out", "--threads", "1"], d, prelude=_STUB)
    assert proc.returncode == 1, proc.stderr
    assert "found a character device" in _table(d / "out")["F40_sine_3mm"]["error"]


@row("beyond: a case file that is a FIFO is refused")
def _(d):
    line = _error(slosh(["fit", _fifo(d, "case.toml"), "--json", d / "f.json"], d))
    assert "case.toml: expected a TOML case file" in line and "named pipe (FIFO)" in line


@row("beyond: a parameter file over the size bound is refused with the bound")
def _(d):
    big = d / "big.json"
    with big.open("wb") as fh:
        fh.truncate(65 * 2**20)  # sparse: 65 MiB of zeros
    line = _error(slosh(["simulate", _a1(d), "--params", big, "--out", d / "s.csv"], d))
    assert "big.json: larger than 64 MiB, the most read for a parameter file (JSON)" in line


# -- bad 3: an output path that is a device -------------------------------------------------


@row("bad 3: --json /dev/full is refused and the device stays a device")
def _(d):
    import stat

    # a private copy of /dev/full (same device numbers): a regression replaces this node,
    # not the machine's /dev/full
    full = d / "full"
    try:
        os.mknod(full, stat.S_IFCHR | 0o666, os.makedev(1, 7))
    except PermissionError:
        pytest.skip("making a device node needs root")
    line = _error(slosh(["tank", "--radius", "0.1", "--fill", "0.5", "--json", full,
                         "--overwrite"], d))
    assert f"--json {full}: is a character device; expected a regular file" in line
    assert stat.S_ISCHR(os.stat(full).st_mode)


@row("beyond: a FIFO where the output file goes is refused, not replaced")
def _(d):
    target = _fifo(d, "out.json")
    line = _error(slosh(["tank", "--radius", "0.1", "--fill", "0.5", "--json", target,
                         "--overwrite"], d))
    assert "is a named pipe (FIFO); expected a regular file" in line
    import stat

    assert stat.S_ISFIFO(os.stat(target).st_mode)


# -- bad 4: the campaign store ----------------------------------------------------------------

_STUB = """
import math
import estimate.campaign.tasks as _tasks
from analogs.errors import InputError as _InputError

FAIL = {}  # record id -> exception class

def _stub_fit(task):
    ids = [c.test.id for c in task.cases]
    for i in ids:
        if i in FAIL and len(ids) == 1:
            raise FAIL[i](f"stub failure of {i}")
    n = [int(c.n_samples) for c in task.cases]
    return {"status": "ok", "error": None, "cases": ids, "model": task.model,
            "solver_status": "Solve_Succeeded", "iterations": 3, "samples": sum(n),
            "rms_residual": 0.05, "noise": 0.05,
            "parameters": {"stub.value": [%r, 0.01, %r, %r, "kg"]}, "derived": {},
            "records": {i: {"amplitude_m": 0.001, "samples": k, "force_noise": 0.05}
                        for i, k in zip(ids, n)}, "warnings": []}

_tasks._fit = _stub_fit
""" % (STUB_MASS, STUB_MASS - 0.02, STUB_MASS + 0.02)


def _campaign(d: Path, names=("F40_sine_1.5mm", "F40_sine_3mm")) -> Path:
    folder = d / "camp"
    folder.mkdir()
    for name in names:
        for ext in ("toml", "csv"):
            (folder / f"{name}.{ext}").write_bytes((CAMPAIGN / f"{name}.{ext}").read_bytes())
    return folder


def _table(out: Path) -> dict[str, dict[str, str]]:
    with (out / "campaign.csv").open() as fh:
        return {r["id"]: r for r in csv.DictReader(fh)}


def _entries(out: Path) -> dict[str, Path]:
    """Store entries by the record ids (or group) of their outcome."""
    found = {}
    for path in (out / "store").glob("*.json"):
        outcome = json.loads(path.read_text())["outcome"]
        found[",".join(outcome.get("cases", [path.stem]))] = path
    return found


def _run_twice(d: Path, damage: Callable[[dict[str, Path]], None], *, prelude: str = _STUB,
               again: list[str] = ()) -> tuple[subprocess.CompletedProcess, dict]:
    folder = _campaign(d)
    argv = ["campaign", folder, "--out", d / "out", "--threads", "1"]
    first = slosh(argv, d, prelude=prelude)
    assert first.returncode == 0, first.stderr
    damage(_entries(d / "out"))
    second = slosh([*argv, *again], d, prelude=_STUB)
    return second, _table(d / "out")


def _rewrite(path: Path, edit: Callable[[dict], object]) -> None:
    entry = json.loads(path.read_text())
    path.write_text(json.dumps(edit(entry)))


@row("bad 4: a store entry with an empty outcome is recomputed with a note")
def _(d):
    proc, rows = _run_twice(d, lambda e: _rewrite(e["F40_sine_3mm"],
                                                  lambda x: x | {"outcome": {}}))
    assert proc.returncode == 0, proc.stderr
    assert "is damaged (expected an outcome object, found {})" in proc.stderr
    assert "1 tasks computed, 2 taken from the store" in proc.stdout
    assert float(rows["F40_sine_3mm"]["stub.value [kg]"]) == STUB_MASS


@row("weak: a store entry that is a list, or a string, is recomputed")
def _(d):
    def damage(e):
        e["F40_sine_3mm"].write_text("[1, 2]")
        e["F40_sine_1.5mm"].write_text('"text"')
    proc, rows = _run_twice(d, damage)
    assert proc.returncode == 0, proc.stderr
    assert "expected a JSON object, found list" in proc.stderr
    assert "expected a JSON object, found str" in proc.stderr
    assert "2 tasks computed, 1 taken from the store" in proc.stdout


@row("weak: an edited store value fails its checksum and is recomputed")
def _(d):
    def damage(e):
        def edit(entry):
            entry["outcome"]["parameters"]["stub.value"][0] = 99.0
            return entry
        _rewrite(e["F40_sine_3mm"], edit)
    proc, rows = _run_twice(d, damage)
    assert proc.returncode == 0, proc.stderr
    assert "does not match its checksum" in proc.stderr
    assert float(rows["F40_sine_3mm"]["stub.value [kg]"]) == STUB_MASS


@row("bad 4: a failure of the environment is not stored: the next run retries it")
def _(d):
    folder = _campaign(d)
    argv = ["campaign", folder, "--out", d / "out", "--threads", "1"]
    first = slosh(argv, d, prelude=_STUB + "\nFAIL['F40_sine_3mm'] = OSError\n")
    assert first.returncode == 1, first.stderr
    error = _table(d / "out")["F40_sine_3mm"]["error"]
    assert "OSError: stub failure" in error and "retried on the next run" in error
    second = slosh(argv, d, prelude=_STUB)  # the cause is gone
    assert second.returncode == 0, second.stderr
    assert _table(d / "out")["F40_sine_3mm"]["status"] == "ok"


@row("beyond: a failure that depends only on the inputs is stored and says so")
def _(d):
    folder = _campaign(d)
    argv = ["campaign", folder, "--out", d / "out", "--threads", "1"]
    prelude = _STUB + "\nFAIL['F40_sine_3mm'] = _InputError\n"
    assert slosh(argv, d, prelude=prelude).returncode == 1
    error = _table(d / "out")["F40_sine_3mm"]["error"]
    assert "depends only on the inputs: kept until they change" in error
    second = slosh(argv, d, prelude=_STUB)  # taken from the store: same inputs, same failure
    # the group of the one good record is that record's fit: two tasks in all
    assert second.returncode == 1 and "0 tasks computed, 2 taken from the store" in second.stdout


@row("bad 4: --overwrite recomputes every stored result")
def _(d):
    proc, _ = _run_twice(d, lambda e: None, again=["--overwrite"])
    assert proc.returncode == 0, proc.stderr
    assert "3 tasks computed, 0 taken from the store" in proc.stdout


@row("bad 4: a record whose fit fails leaves its group, which is fitted with the others")
def _(d):
    folder = _campaign(d, ("F40_sine_1.5mm", "F40_sine_3mm", "F40_sweep_0.6mm"))
    proc = slosh(["campaign", folder, "--out", d / "out", "--threads", "1"], d,
                 prelude=_STUB + "\nFAIL['F40_sweep_0.6mm'] = _InputError\n")
    assert proc.returncode == 1, proc.stderr
    rows = _table(d / "out")
    group = next(r for r in rows.values() if r["kind"] == "group")
    assert group["status"] == "ok" and group["records"] == "F40_sine_1.5mm;F40_sine_3mm"
    assert "F40_sweep_0.6mm (its fit failed)" in group["excluded"]


# -- bad 5: a failed fit travels on ------------------------------------------------------------


@row("bad 5: montecarlo refuses a fit marked converged: false")
def _(d):
    line = _error(slosh(["montecarlo", _fit_file(d, converged=False), _a1(d), "--samples", "2",
                         "--local", "--out", d / "mc"], d))
    assert "fit.json: the fit did not converge (`converged: false`" in line and "--force" in line
    assert not (d / "mc").exists()


@row("bad 5: export refuses a fit marked converged: false")
def _(d):
    line = _error(slosh(["export", _fit_file(d, converged=False), "--out", d / "c",
                         "--no-build"], d))
    assert "the fit did not converge" in line and not (d / "c").exists()


@row("bad 5: simulate takes a non-converged fit with --force, and warns")
def _(d):
    fit = _fit_file(d, converged=False)
    line = _error(slosh(["simulate", _a1(d), "--params", fit, "--out", d / "s.csv"], d))
    assert "the fit did not converge" in line
    proc = slosh(["simulate", _a1(d), "--params", fit, "--out", d / "s.csv", "--force"], d)
    assert proc.returncode == 0, proc.stderr
    assert "warning: " in proc.stderr and "used because of --force" in proc.stderr
    assert (d / "s.csv").exists()


# slow: IPOPT runs its 600 iterations on a record with nothing to fit (17-36 s)
@row("bad 5: a force column of pure noise fits with a warning that R^2 is near 0", slow=True)
def _(d):
    data = np.loadtxt(EXAMPLES / "A1.csv", delimiter=",", skiprows=1)[:1001]
    data[:, 2] = np.random.default_rng(7).normal(0.0, 0.05, data.shape[0])
    text = "time,displacement,force\n" + "".join(f"{a:.12g},{b:.12g},{c:.12g}\n" for a, b, c in data)
    # the classical input (filtered displacement) keeps the fit short: IPOPT runs to its
    # iteration limit on a record with nothing to fit (2.5 min with the estimated input)
    proc = slosh(["fit", _a1(d, "noise", csv_text=text), "--json", d / "f.json", "--input",
                  "filtered"], d)
    assert "the model explains almost nothing of the measurement (R^2 = " in proc.stderr
    assert json.loads((d / "f.json").read_text())["r_squared"] < 0.1


# -- weak rows ---------------------------------------------------------------------------------


def _dry_mass(value: str):
    return lambda s: s.replace("dry_mass = 1.2", f"dry_mass = {value}")


for _value in ("1e30", "1e308"):
    @row(f"weak: dry_mass = {_value} is refused before any computation")
    def _(d, value=_value):
        line = _error(slosh(["fit", _a1(d, toml=_dry_mass(value)), "--json", d / "f.json"], d))
        assert "A1.toml: [rig] dry_mass: expected 1e-06 to 1e+06 kg" in line


@row("weak: radius = 1e300 is refused naming the key")
def _(d):
    line = _error(slosh(["fit", _a1(d, toml=lambda s: s.replace("radius = 0.1016",
                                                                "radius = 1e300")),
                         "--json", d / "f.json"], d))
    assert "A1.toml: [tank] radius: expected 1e-06 to 1000 m" in line


@row("weak: a force of 1e300 everywhere is refused naming the column")
def _(d):
    data = np.loadtxt(EXAMPLES / "A1.csv", delimiter=",", skiprows=1)
    text = "time,displacement,force\n" + "".join(f"{a:.12g},{b:.12g},1e300\n" for a, b, _ in data)
    line = _error(slosh(["fit", _a1(d, csv_text=text), "--json", d / "f.json"], d))
    assert "A1.csv: column `force`: expected a force of magnitude up to 1e+09 N" in line


@row("beyond: slosh tank --radius 1e300 names the option and the range")
def _(d):
    line = _error(slosh(["tank", "--radius", "1e300", "--fill", "0.5"], d))
    assert "--radius 1e+300: expected 1e-06 to 1000 m (the range accepted for a length)" in line


@row("weak: a CSV cut inside its last number is refused")
def _(d):
    text = (EXAMPLES / "A1.csv").read_text()[:-5]  # "...,-5.2252685571\n" -> "-5.2252685"
    line = _error(slosh(["simulate", _a1(d, csv_text=text), "--params", _params(d), "--out",
                         d / "s.csv"], d))
    assert "A1.csv: line 3002: the file ends inside a number" in line


@row("beyond: a CSV without a final line end but whole is accepted")
def _(d):
    text = (EXAMPLES / "A1.csv").read_text()[:-1]
    # the case loads; the command then stops at the fit file (no simulation needed)
    line = _error(slosh(["simulate", _a1(d, csv_text=text), "--params",
                         _fit_file(d, converged=False), "--out", d / "s.csv"], d))
    assert "the fit did not converge" in line


def _deep(kind: str, depth: int = 50_000) -> str:
    return "[" * depth + "]" * depth if kind == "json" else "x = " + "[" * depth + "]" * depth


@row("weak: a 50,000-deep TOML case file is one line, not a RecursionError")
def _(d):
    line = _error(slosh(["fit", _a1(d, toml=lambda s: s + _deep("toml") + "\n"),
                         "--json", d / "f.json"], d))
    assert "A1.toml: nested deeper than 64 arrays or tables" in line


@row("weak: a 50,000-deep JSON parameter file is one line, not a RecursionError")
def _(d):
    (d / "deep.json").write_text(_deep("json"))
    line = _error(slosh(["simulate", _a1(d), "--params", d / "deep.json", "--out",
                         d / "s.csv"], d))
    assert "deep.json: nested deeper than 64 arrays or tables" in line


@row("weak: a 50,000-deep case file fails its record, not the whole campaign")
def _(d):
    folder = _campaign(d)
    toml = folder / "F40_sine_3mm.toml"
    toml.write_text(toml.read_text() + _deep("toml") + "\n")
    proc = slosh(["campaign", folder, "--out", d / "out", "--threads", "1"], d, prelude=_STUB)
    assert proc.returncode == 1, proc.stderr
    rows = _table(d / "out")
    assert "nested deeper than 64" in rows["F40_sine_3mm"]["error"]
    assert rows["F40_sine_1.5mm"]["status"] == "ok"


@row("weak: [predicton] (a typo) is a warning with the nearest name; --strict refuses it")
def _(d):
    case = _a1(d, toml=lambda s: s.replace("[prediction]", "[predicton]"))
    stop = _fit_file(d, converged=False)  # the case loads, then the command stops here
    proc = slosh(["simulate", case, "--params", stop, "--out", d / "s.csv"], d)
    assert "the fit did not converge" in _error(proc)
    assert ("warning: A1.toml: unknown table `[predicton]` (ignored); did you mean "
            "`[prediction]`?") in proc.stderr
    line = _error(slosh(["simulate", case, "--params", stop, "--out", d / "t.csv",
                         "--strict"], d))
    assert "A1.toml: unknown table `[predicton]`; did you mean `[prediction]`?" in line


@row("beyond: an unknown key in a table names the table, the key and the nearest key")
def _(d):
    case = _a1(d, toml=lambda s: s.replace("kinematic_viscosity", "kinematic_viscosty"))
    proc = slosh(["simulate", case, "--params", _params(d), "--out", d / "s.csv"], d)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    assert "A1.toml: [liquid] kinematic_viscosity: missing key" in proc.stderr
    assert ("A1.toml: unknown key `[liquid] kinematic_viscosty` (ignored); did you mean "
            "`[liquid] kinematic_viscosity`?") in proc.stderr


@row("weak: campaign groups of the wrong type are refused at discovery")
def _(d):
    folder = _campaign(d)
    (folder / "campaign.toml").write_text("groups = 5\n")
    line = _error(slosh(["campaign", folder, "--out", d / "out"], d))
    assert "campaign.toml: groups: expected tables `[groups.NAME]`" in line


@row("weak: a bad [groups.X] model is blamed on that key, not on --model")
def _(d):
    folder = _campaign(d)
    (folder / "campaign.toml").write_text('[groups.low]\nrecords = ["F40_*"]\n'
                                          'model = "fixed,p0"\n')
    proc = slosh(["campaign", folder, "--out", d / "out"], d)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "campaign.toml: [groups.low] model 'fixed,p0': `p0`" in proc.stderr
    assert "--model" not in proc.stderr


@row("weak: --scheduler tcp://127.0.0.1:notaport is one line naming the option")
def _(d):
    line = _error(slosh(["montecarlo", _fit_file(d), _a1(d), "--samples", "2", "--scheduler",
                         "tcp://127.0.0.1:notaport", "--out", d / "mc"], d))
    assert "--scheduler 'tcp://127.0.0.1:notaport': not a scheduler address" in line


def _lab(d: Path, unit: str | None = None, *, complex_force: bool = False,
         cut: float | None = None, fmt: str = "h5") -> Path:
    """A1 as an HDF5 (or MAT v5, TDMS) file with a [data.columns] table."""
    data = np.loadtxt(EXAMPLES / "A1.csv", delimiter=",", skiprows=1)
    t, x, f = data.T
    if complex_force:
        f = f + 1j * f
    path = d / f"A1.{fmt}"
    if fmt == "h5":
        import h5py

        with h5py.File(path, "w") as h:
            h["t"], h["x"], h["f"] = t, x, f
        columns = 'time = "t"\ndisplacement = "x"\nforce = ' + (
            f'{{ channel = "f", unit = "{unit}" }}' if unit is not None else '"f"')
    elif fmt == "mat":
        import scipy.io

        scipy.io.savemat(path, {"t": t[:, None], "x": x[:, None], "f": f[:, None]})
        columns = 'time = "t"\ndisplacement = "x"\nforce = "f"'
    else:
        from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

        with TdmsWriter(path) as w:
            w.write_segment([RootObject({}), GroupObject("g"), ChannelObject("g", "t", t),
                             ChannelObject("g", "x", x), ChannelObject("g", "f", f)])
        columns = 'time = "g/t"\ndisplacement = "g/x"\nforce = "g/f"'
    if cut is not None:
        raw = path.read_bytes()
        path.write_bytes(raw[:int(len(raw) * cut)])
    return _a1(d, toml=lambda s: s.replace('data = "A1.csv"', f'data = "A1.{fmt}"')
               + "\n[data.columns]\n" + columns + "\n")


@row("weak: a malformed unit is one line naming [data.columns], not a pint AssertionError")
def _(d):
    pytest.importorskip("h5py")
    pytest.importorskip("pint")
    line = _error(slosh(["simulate", _lab(d, "-"), "--params", _params(d), "--out",
                         d / "s.csv"], d))
    assert '[data.columns] force: unknown unit "-": not a unit expression' in line


@row("weak: a complex-valued channel is refused by name, not cast with a raw warning")
def _(d):
    pytest.importorskip("h5py")
    proc = slosh(["simulate", _lab(d, complex_force=True), "--params", _params(d), "--out",
                  d / "s.csv"], d)
    line = _error(proc)
    assert "A1.h5: channel `f` ([data.columns] force): expected real numbers, found complex" in line
    assert "ComplexWarning" not in proc.stderr


@row("weak: a damaged TDMS file is reported as damaged, not 'channel not found'")
def _(d):
    pytest.importorskip("nptdms")
    line = _error(slosh(["simulate", _lab(d, fmt="tdms", cut=0.6), "--params", _params(d),
                         "--out", d / "s.csv"], d))
    assert "A1.tdms: damaged TDMS file" in line and "not found" not in line


@row("weak: a damaged MAT file is reported as damaged, not 'channel not found'")
def _(d):
    line = _error(slosh(["simulate", _lab(d, fmt="mat", cut=0.6), "--params", _params(d),
                         "--out", d / "s.csv"], d))
    assert "A1.mat: not a readable MAT file (damaged" in line and "not found" not in line


def _loaded(pid: int, library: str, timeout: float = TIMEOUT) -> None:
    """Wait until process ``pid`` has mapped a shared object whose path holds ``library``."""
    deadline = time.monotonic() + timeout
    while library not in Path(f"/proc/{pid}/maps").read_text():
        assert time.monotonic() < deadline, f"{library} not loaded within {timeout} s"
        time.sleep(0.02)


@row("weak: Ctrl-C during start-up is one line and 130, not a 20-line traceback")
def _(d):
    """SIGINT while the command loads its libraries (NumPy's core, then CasADi's, mapped
    into the process: the moments are read from /proc, so a loaded machine does not move
    the signal before Python's own start, which no program can answer)."""
    if not Path("/proc/self/maps").exists():
        pytest.skip("needs Linux /proc")
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}
    code = "import sys\nfrom estimate.cli import main\nsys.exit(main())\n"
    for library in ("_multiarray_umath", "libcasadi"):
        proc = subprocess.Popen([sys.executable, "-c", code, "fit", str(_a1(d)), "--json",
                                 str(d / "f.json")], cwd=d, env=env, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        try:
            _loaded(proc.pid, library)
            proc.send_signal(signal.SIGINT)
            _, err = proc.communicate(timeout=TIMEOUT)
        finally:
            if proc.poll() is None:
                proc.kill()
        assert proc.returncode == 130, err
        assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
        assert not (d / "f.json").exists()


@row("weak: an interrupt after the outputs were written exits 0 and says they are complete")
def _(d):
    prelude = """
    import os, signal
    from estimate import outputs
    _commit = outputs.Outputs._commit
    def _then_interrupt(self, temps):
        _commit(self, temps)
        os.kill(os.getpid(), signal.SIGINT)
    outputs.Outputs._commit = _then_interrupt
    """
    proc = slosh(["tank", "--radius", "0.1", "--fill", "0.5", "--json", d / "t.json"], d,
                 prelude=prelude)
    assert proc.returncode == 0, proc.stderr
    assert "SIGINT arrived after the command had written its outputs" in proc.stderr
    assert json.loads((d / "t.json").read_text())


def _spinning(d: Path, **spin: str) -> Path:
    values = {"rate": "6.0", "radius": "0.4", "nutation_angle": "0.06",
              "nutation_frequency": "0.3"} | spin
    text = (EXAMPLES / "A1.toml").read_text().replace('rig = "lateral"', 'rig = "spinning"')
    text = text.replace('excitation = "measured"\n', "").replace('"A1.csv"', '"S1.csv"')
    text += "\n[rig.spin]\n" + "".join(f"{k} = {v}\n" for k, v in values.items())
    t = np.arange(200) * 0.01
    cols = ("force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z")
    (d / "S1.csv").write_text("time," + ",".join(cols) + "\n" + "".join(
        f"{ti:.2f}," + ",".join(f"{np.sin(ti + k):.6f}" for k in range(6)) + "\n" for ti in t))
    (d / "S1.toml").write_text(text)
    return d / "S1.toml"


@row("weak: a spin rate of 1e10 is blamed on the case file's key, before any simulation")
def _(d):
    line = _error(slosh(["simulate", _spinning(d, rate="1e10"), "--params", _params(d),
                         "--out", d / "s.csv"], d))
    assert "S1.toml: [rig.spin] rate: expected a magnitude up to 1000 rad/s" in line
    assert "p.json" not in line


@row("weak: a spin radius of 1e6 m is blamed on the case file's key")
def _(d):
    line = _error(slosh(["simulate", _spinning(d, radius="1e6"), "--params", _params(d),
                         "--out", d / "s.csv"], d))
    assert "S1.toml: [rig.spin] radius: expected a magnitude up to 1000 m" in line


def _spacecraft(d: Path, edit: Callable[[str], str]) -> Path:
    (d / "sc.toml").write_text(edit((EXAMPLES / "spacecraft.toml").read_text()))
    return d / "sc.toml"


@row("weak: ntc with an analog mass of 1e30 names the spacecraft file's key")
def _(d):
    proc = slosh(["ntc", _spacecraft(d, lambda s: s.replace("mass = 20.0", "mass = 1e30"))], d)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    assert "sc.toml [[analog]] #1: `mass`: expected 1e-06 to 1e+06 kg" in proc.stderr


@row("weak: ntc with a tank radius of 1e6 m names the key")
def _(d):
    proc = slosh(["ntc", _spacecraft(d, lambda s: s.replace("radius = 0.8 ", "radius = 1e6 "))],
                 d)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    assert "sc.toml [tank]: `radius`: expected a magnitude up to 1000 m" in proc.stderr


@row("weak: a bus whose inertias violate the triangle inequality is refused")
def _(d):
    proc = slosh(["ntc", _spacecraft(d, lambda s: s.replace("inertia_z = 600.0",
                                                            "inertia_z = 900.0"))], d)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    assert "`inertia_z` = 900 kg m^2 exceeds the sum of the other two" in proc.stderr


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow if n in SLOW else ())
                                  for n in ROWS])
def test_attempt(name, tmp_path):
    ROWS[name](tmp_path)
