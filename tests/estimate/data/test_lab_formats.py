"""Lab data formats: the bundled example A1 written as TDMS, MAT v5, MAT v7.3 and HDF5 by
those libraries' own writers (in lbf, mm, ms, kN), read back through ``[data.columns]``,
gives the CSV's samples and the CSV's fit; bad channels and units are one-line errors."""

import re
from pathlib import Path

import numpy as np
import pytest

from estimate import FitProblem, fit, load_case, model_from_spec
from estimate.cli import main
from estimate.data import CaseError

nptdms = pytest.importorskip("nptdms")
h5py = pytest.importorskip("h5py")
pint = pytest.importorskip("pint")
import scipy.io  # noqa: E402

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"
UREG = pint.UnitRegistry()
#: Same estimates as the CSV: the arrays agree to a unit conversion's round-off (~1e-16),
#: which IPOPT's deterministic iterations carry through far below this.
SAME_FIT_RTOL = 1e-9


def _csv():
    data = np.loadtxt(EXAMPLES / "A1.csv", delimiter=",", skiprows=1)
    return data[:, 0], data[:, 1], data[:, 2]


def _from(si: np.ndarray, unit: str, si_unit: str) -> np.ndarray:
    """``si`` expressed in ``unit`` (what a lab's acquisition would have recorded)."""
    return UREG.Quantity(si, si_unit).to(unit).magnitude


def _case(folder: Path, data: str, columns: str | None) -> Path:
    """A1.toml pointing at ``data``, with a ``[data.columns]`` table when given."""
    text = (EXAMPLES / "A1.toml").read_text().replace('data = "A1.csv"', f'data = "{data}"')
    if columns is not None:
        text += "\n[data.columns]\n" + columns
    path = folder / f"{Path(data).stem}.toml"
    path.write_text(text)
    return path


def _tdms(folder: Path, *, waveform: bool = False) -> Path:
    """TDMS as LabVIEW writes it: a group of channels, force in lbf."""
    from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

    t, x, f = _csv()
    path = folder / "A1.tdms"
    wf = {"wf_increment": 0.01, "wf_start_offset": 0.0} if waveform else {}
    with TdmsWriter(path) as w:
        objs = [RootObject({"title": "A1"}), GroupObject("Loads")]
        if not waveform:
            objs.append(ChannelObject("Loads", "Time", t, {"unit_string": "s"}))
        objs += [ChannelObject("Loads", "X", x, {"unit_string": "m", **wf}),
                 ChannelObject("Loads", "Fx", _from(f, "lbf", "N"), wf)]
        w.write_segment(objs)
    return path


TDMS_COLUMNS = ('time = "Loads/Time"\ndisplacement = "X"\n'
                'force = { channel = "Fx", unit = "lbf" }\n')


def _mat5(folder: Path) -> Path:
    """MAT v5 by scipy.io.savemat: column vectors, displacement in mm."""
    t, x, f = _csv()
    path = folder / "A1_v5.mat"
    scipy.io.savemat(path, {"t": t[:, None], "x_mm": _from(x, "mm", "m")[:, None],
                            "Fx": f[:, None]}, format="5")
    return path


MAT5_COLUMNS = 'time = "t"\ndisplacement = { channel = "x_mm", unit = "mm" }\nforce = "Fx"\n'


def _mat73(folder: Path) -> Path:
    """MAT v7.3 as MATLAB writes it: HDF5 behind a 512-byte MATLAB header, each variable a
    dataset of the transposed (1, N) shape with its MATLAB_class; time in ms, force in kN."""
    t, x, f = _csv()
    path = folder / "A1_v73.mat"
    with h5py.File(path, "w", userblock_size=512) as h:
        for name, values in (("t_ms", _from(t, "ms", "s")), ("x", x), ("Fx", _from(f, "kN", "N"))):
            ds = h.create_dataset(name, data=values[None, :])
            ds.attrs["MATLAB_class"] = np.bytes_("double")
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 " \
             b"HDF5 schema 1.00 ."
    with path.open("r+b") as fh:
        fh.write(header.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02" + b"IM")
    return path


MAT73_COLUMNS = ('time = { channel = "t_ms", unit = "ms" }\ndisplacement = "x"\n'
                 'force = { channel = "Fx", unit = "kN" }\n')


def _hdf5(folder: Path) -> Path:
    """HDF5 by h5py: datasets in a group, units as attributes (force in lbf, displacement
    in mm, read from the file)."""
    t, x, f = _csv()
    path = folder / "A1.h5"
    with h5py.File(path, "w") as h:
        run = h.create_group("run1")
        run.create_dataset("time", data=t).attrs["units"] = "s"
        run.create_dataset("x", data=_from(x, "mm", "m")).attrs["units"] = "mm"
        run.create_dataset("Fx", data=_from(f, "lbf", "N")).attrs["unit"] = "lbf"
    return path


HDF5_COLUMNS = 'time = "run1/time"\ndisplacement = "run1/x"\nforce = "/run1/Fx"\n'

FORMATS = {"tdms": (_tdms, TDMS_COLUMNS), "mat_v5": (_mat5, MAT5_COLUMNS),
           "mat_v73": (_mat73, MAT73_COLUMNS), "hdf5": (_hdf5, HDF5_COLUMNS)}


@pytest.fixture(scope="module")
def lab_cases(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("lab")
    return {kind: _case(folder, write(folder).name, columns)
            for kind, (write, columns) in FORMATS.items()}


def test_mat_v73_file_is_what_matlab_and_scipy_recognise(lab_cases):
    from scipy.io.matlab import matfile_version

    path = lab_cases["mat_v73"].with_name("A1_v73.mat")
    with path.open("rb") as fh:
        assert matfile_version(fh) == (2, 0)
    with pytest.raises(NotImplementedError):  # scipy reads up to v7; v7.3 goes through h5py
        scipy.io.loadmat(path)


@pytest.mark.parametrize("kind", list(FORMATS))
def test_lab_file_gives_the_csv_samples_in_si(lab_cases, kind):
    csv = load_case(EXAMPLES / "A1.toml")
    case = load_case(lab_cases[kind])
    assert case.data_path.suffix in (".tdms", ".mat", ".h5")
    for name in ("time", "displacement", "force"):
        np.testing.assert_allclose(getattr(case, name), getattr(csv, name), rtol=1e-14,
                                   atol=1e-15 * np.abs(getattr(csv, name)).max(), err_msg=name)
        assert not getattr(case, name).flags.writeable


def test_lab_files_fit_to_the_csv_estimates(lab_cases):
    csv = load_case(EXAMPLES / "A1.toml")
    model = model_from_spec("fixed,p1", csv)
    ref = fit(FitProblem.build(csv, model))
    assert ref.converged
    for kind, path in lab_cases.items():
        res = fit(FitProblem.build(load_case(path), model))
        assert res.converged, kind
        assert res.names == ref.names
        # the same fit: within SAME_FIT_RTOL, or a millionth of a standard error for an
        # estimate near zero (a hinge spring at 4e-9 N m/rad: the first stage's SciPy
        # search turns round-off in the converted units into 1e-15 there)
        diff = np.abs(res.values - ref.values)
        assert np.all(diff <= SAME_FIT_RTOL * np.abs(ref.values)
                      + 1e-6 * np.nan_to_num(ref.stderr)), kind
        np.testing.assert_allclose(res.stderr, ref.stderr, rtol=SAME_FIT_RTOL, err_msg=kind)


def test_tdms_waveform_channels_need_no_time_channel(tmp_path):
    _tdms(tmp_path, waveform=True)
    path = _case(tmp_path, "A1.tdms", 'displacement = "X"\nforce = { channel = "Fx", unit = "lbf" }\n')
    case = load_case(path)
    np.testing.assert_allclose(case.time, load_case(EXAMPLES / "A1.toml").time, atol=1e-12)


def test_without_a_columns_table_channels_are_looked_up_by_our_names(tmp_path):
    t, x, f = _csv()
    with h5py.File(tmp_path / "plain.h5", "w") as h:
        for name, values in (("time", t), ("displacement", x), ("force", f)):
            h[name] = values
    case = load_case(_case(tmp_path, "plain.h5", None))
    np.testing.assert_array_equal(case.force, f)


# ---------------------------------------------------------------------------------------------
# errors: one line naming the file and the channel or key


def _one_problem(path: Path) -> str:
    with pytest.raises(CaseError) as info:
        load_case(path)
    assert len(info.value.problems) == 1, info.value.problems
    message = str(info.value)
    assert "\n" not in message
    return message


def test_a_wrong_unit_name_names_the_key_file_and_channel(tmp_path):
    _tdms(tmp_path)
    path = _case(tmp_path, "A1.tdms", TDMS_COLUMNS.replace('"lbf"', '"lbx"'))
    message = _one_problem(path)
    assert re.fullmatch(r'A1\.toml: \[data\.columns\] force: unknown unit "lbx": not a unit pint '
                        r'knows \(expected a force unit such as "N", "kN" or "lbf"\); for channel '
                        r"`Fx` of A1\.tdms", message), message


def test_a_unit_of_the_wrong_kind_is_refused(tmp_path):
    _mat5(tmp_path)
    path = _case(tmp_path, "A1_v5.mat", MAT5_COLUMNS.replace('"mm"', '"lb"'))
    assert re.search(r'\[data\.columns\] displacement: unit "lb" \(\[mass\]\) is not a length '
                     r"unit .* for channel `x_mm` of A1_v5\.mat", _one_problem(path))


def test_a_units_attribute_of_the_wrong_kind_names_the_channel(tmp_path):
    _hdf5(tmp_path)
    with h5py.File(tmp_path / "A1.h5", "r+") as h:
        h["run1/Fx"].attrs["unit"] = "V"
    message = _one_problem(_case(tmp_path, "A1.h5", HDF5_COLUMNS))
    assert message.startswith("A1.h5: channel `run1/Fx` ([data.columns] force): the file gives "
                              'unit "V"'), message


@pytest.mark.parametrize("kind", list(FORMATS))
def test_a_missing_channel_names_the_file_and_the_channel(tmp_path, kind):
    write, columns = FORMATS[kind]
    data = write(tmp_path).name
    wrong = re.sub(r'(force = (\{ channel = )?)"[^"]+"', r'\1"Fy"', columns)
    message = _one_problem(_case(tmp_path, data, wrong))
    assert message.startswith(f"{data}: channel `Fy` ([data.columns] force): not found; the file "
                              "has "), message


def test_missing_channel_is_one_line_with_status_2_on_the_command_line(tmp_path, capsys):
    _tdms(tmp_path)
    path = _case(tmp_path, "A1.tdms", TDMS_COLUMNS.replace('"X"', '"Xpos"'))
    assert main(["fit", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert err.startswith("slosh fit: error: A1.tdms: channel `Xpos` ([data.columns] "
                          "displacement): not found; the file has `Loads/Time`, `Loads/X`, "
                          "`Loads/Fx`"), err


def test_wrong_unit_is_one_line_with_status_2_on_the_command_line(tmp_path, capsys):
    _mat73(tmp_path)
    path = _case(tmp_path, "A1_v73.mat", MAT73_COLUMNS.replace('"ms"', '"fortnights_per_s"'))
    assert main(["fit", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "A1_v73.toml: [data.columns] time: unknown unit " \
        '"fortnights_per_s"' in err and "channel `t_ms` of A1_v73.mat" in err, err


def test_samples_are_checked_as_a_csv_s(tmp_path):
    t, x, f = _csv()
    f = f.copy()
    f[7] = np.nan
    t = t.copy()
    t[100] = t[99]
    with h5py.File(tmp_path / "bad.h5", "w") as h:
        h["time"], h["displacement"], h["force"] = t, x, f
    with pytest.raises(CaseError) as info:
        load_case(_case(tmp_path, "bad.h5", None))
    problems = info.value.problems
    assert problems == [
        "bad.h5: channel `force`: expected finite numbers, found 1 NaN or inf value(s) at index 7",
        "bad.h5: channel `time`: expected strictly increasing times, found 1 decrease(s) or "
        "repeat(s) at index 100"], problems


def test_channels_of_different_lengths_and_non_vectors_are_refused(tmp_path):
    t, x, f = _csv()
    with h5py.File(tmp_path / "ragged.h5", "w") as h:
        h["time"], h["displacement"], h["force"] = t, x[:-1], f
    assert _one_problem(_case(tmp_path, "ragged.h5", None)) == (
        "ragged.h5: channels: expected the same number of samples in every channel, found "
        "`time` (time) 3001, `displacement` (displacement) 3000, `force` (force) 3001")
    with h5py.File(tmp_path / "matrix.h5", "w") as h:
        h["time"], h["displacement"], h["force"] = t, x, np.tile(f, (2, 1))
    assert "matrix.h5: channel `force` (column `force`, looked up by name without " \
        "[data.columns]): expected a vector of numbers, found shape (2, 3001)" \
        == _one_problem(_case(tmp_path, "matrix.h5", None))


def test_the_memory_budget_is_checked_before_reading(tmp_path, monkeypatch):
    _mat5(tmp_path)
    monkeypatch.setenv("SLOSH_MEMORY_BUDGET", "32M")  # 2048 samples
    message = _one_problem(_case(tmp_path, "A1_v5.mat", MAT5_COLUMNS))
    assert message.startswith("A1_v5.mat: channel `t`: 3001 samples; a fit needs"), message
    assert "decimate by 2" in message


def test_columns_table_problems_name_the_case_file(tmp_path):
    _hdf5(tmp_path)
    bad = 'time = 3\nforce = { channel = "run1/Fx", units = "lbf" }\nspeed = "v"\n'
    with pytest.raises(CaseError) as info:
        load_case(_case(tmp_path, "A1.h5", bad))
    problems = info.value.problems
    assert any(p.startswith("A1.toml: [data.columns] time: expected a channel name") for p in problems)
    assert any("[data.columns] force: unknown key(s) `units`" in p for p in problems), problems
    csv_case = _case(tmp_path, "A1.csv", 'force = "Fx"\n')
    (tmp_path / "A1.csv").write_bytes((EXAMPLES / "A1.csv").read_bytes())
    assert _one_problem(csv_case).startswith("A1.toml: [data]: applies to TDMS, MAT and HDF5")


def test_a_damaged_file_is_a_problem_not_a_traceback(tmp_path):
    (tmp_path / "A1.tdms").write_bytes(b"not a tdms file at all")
    assert _one_problem(_case(tmp_path, "A1.tdms", TDMS_COLUMNS)).startswith(
        "A1.tdms: not a readable TDMS file (")


def test_a_missing_optional_library_names_the_extra(tmp_path, monkeypatch):
    import sys

    from analogs.errors import MissingDependency

    _tdms(tmp_path)
    monkeypatch.setitem(sys.modules, "nptdms", None)  # `import nptdms` raises ImportError
    with pytest.raises(MissingDependency, match=r"A1\.tdms: reading this file needs npTDMS, an "
                       r"optional dependency: `python3 -m pip install '\.\[lab\]'`"):
        load_case(_case(tmp_path, "A1.tdms", TDMS_COLUMNS))
