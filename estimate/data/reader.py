"""``load_case``: a case file (TOML) and the data file it names (a CSV, or a TDMS, MAT or HDF5
file read by :mod:`estimate.data.lab_formats`), validated at once."""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping
from pathlib import Path

from analogs.errors import InputError

from ..inputs import file_kind, parse_toml, read_input
from ._csv import read_csv
from ._keys import Asked, UnknownKey, unknown_keys
from ._toml import Checker, read_tables, test_kind
from .case import Case, CaseError
from .lab_formats import LAB_SUFFIXES, is_lab_file, read_lab
from .plausible_units import ImplausibleUnit, sampling_problem, unit_warnings

__all__ = ["MAX_CASE_FILE_BYTES", "UnknownKey", "load_case"]

#: Largest case file read [bytes]: a case file holds a few short tables, the samples are
#: in its CSV.
MAX_CASE_FILE_BYTES = 2**20


def _not_a_file(path: Path) -> str | None:
    """What ``path`` is when it exists and is not a regular file ("a folder", "a named pipe
    (FIFO)", ...)."""
    return file_kind(path)


def load_case(path: str | os.PathLike[str], *, strict: bool = False,
              allowance: int = 1) -> Case:
    """Load and validate a test case (TOML file plus the CSV, TDMS, MAT or HDF5 file it names).

    The case file must be a regular file of at most :data:`MAX_CASE_FILE_BYTES` bytes nested
    at most :data:`estimate.inputs.MAX_NESTING` levels; numbers must lie in
    :data:`~estimate.data.case.PHYSICAL_RANGES`. A key or table the reader does not know (a
    typo such as ``[predicton]``) is reported with the nearest known name
    (:mod:`estimate.data._keys`): a :class:`UnknownKey` warning, or a problem with
    ``strict``.

    Parameters
    ----------
    path : str or path-like
        The TOML case file.
    strict : bool, default False
        Unknown keys and tables are errors instead of warnings (``--strict``).
    allowance : int, default 1
        The command decimates the record by up to this factor before it fits it (``slosh
        fit``'s default for a long lateral record sampled far above the slosh band,
        ``--decimate K``): the record may hold that many times more samples than the
        memory budget allows a fit (:mod:`estimate.data.budget`); the fit checks the budget
        again on the samples it keeps. ``[test] decimate`` sets it for its own record.

    Returns
    -------
    Case
        Frozen case with read-only arrays ``time`` [s], ``displacement`` [m] (or None) and
        ``force`` [N].

    Raises
    ------
    CaseError
        Listing every problem found in the TOML and data files at once.
    MissingDependency
        When the data file is a TDMS, MAT or HDF5 file and the optional ``lab`` extra
        (npTDMS, h5py, pint) is not installed.

    Examples
    --------
    >>> from estimate.data import load_case
    >>> case = load_case("examples/A1.toml")            # doctest: +SKIP
    >>> case.rig.dry_mass, case.n_samples               # doctest: +SKIP
    (1.2, 3001)
    """
    toml_path = Path(path)
    fname = toml_path.name
    try:
        kind = _not_a_file(toml_path)
        if kind:
            raise CaseError([f"{fname}: expected a TOML case file at `{toml_path}`, found {kind}"])
        raw = read_input(toml_path, "a TOML case file", limit=MAX_CASE_FILE_BYTES)
    except FileNotFoundError:
        raise CaseError([f"{fname}: case file not found (expected a TOML file at "
                         f"`{toml_path}`)"]) from None
    except OSError as exc:
        raise CaseError([f"{fname}: cannot read the case file ({exc.strerror or exc})"]) from None
    except CaseError:
        raise
    except InputError as exc:
        raise CaseError([f"{fname}: {str(exc).split(': ', 1)[-1]}; a case file holds a few "
                         "short tables and names its data file in [test] data"]) from None
    try:
        doc = parse_toml(raw, fname)  # a byte order mark is accepted
    except InputError as exc:
        raise CaseError([str(exc)]) from None

    doc = Asked(doc)
    doc.get("data")  # [data] belongs to lab files; a CSV case with one is refused below
    ck = Checker(fname)
    test, tank, liquid, rig, pred_present, prediction = read_tables(ck, doc)
    excitation, rig_kind = test_kind(doc)
    t_table = doc.get("test")

    problems = ck.problems
    from .motion import extra_columns, motion_columns

    motion = motion_columns(doc)  # a six-axis record's motion columns, by axis
    notes: list[str] = []
    unitless: dict[str, str] = {}  # lab-file columns read with no unit, and their channels
    arrays = None
    data_path: Path | None = None
    data_name = t_table.get("data") if isinstance(t_table, Mapping) else None
    if isinstance(data_name, str) and data_name.strip():
        data_path = Path(data_name)
        if not data_path.is_absolute():
            data_path = toml_path.parent / data_path
        lab = is_lab_file(data_path)
        what = f"a {LAB_SUFFIXES[data_path.suffix.lower()]} file" if lab else "a CSV file"
        kind = _not_a_file(data_path)
        if kind:
            problems.append(f"{fname}: [test] data: expected {what} at `{data_path}`, "
                            f"found {kind}")
        elif not data_path.is_file():
            problems.append(f"{fname}: [test] data: data file not found (expected {what} "
                            f"at `{data_path}`)")
        elif not lab and "data" in doc:
            problems.append(f"{fname}: [data]: applies to TDMS, MAT and HDF5 data files "
                            f"({', '.join(LAB_SUFFIXES)}); a CSV names its columns in its "
                            "header (`time,displacement,force`, SI units)")
        else:
            csv_problems: list[str] = []
            uniform = not (isinstance(t_table, Mapping) and "resample_hz" in t_table)
            # a decimated record is read with as many more samples as it keeps fewer
            factor = test.decimate if test is not None and test.decimate else 1
            # what the budget admits: the case's own decimation, or the command's
            read = factor if test is None or test.decimate is not None else max(allowance, 1)
            if lab and motion is not None:
                csv_problems.append(f"{fname}: [rig.motion]: a six-axis record is read from a "
                                    f"CSV file (`time`, the motion columns, the channels); "
                                    f"found {what} (export it to CSV)")
            elif lab:
                arrays = read_lab(data_path, fname, doc, excitation, rig_kind, rig, csv_problems,
                                  uniform=uniform, unitless=unitless, decimate=read)
            else:
                arrays = read_csv(data_path, excitation, csv_problems, rig_kind, uniform=uniform,
                                  motion=motion, decimate=read)
            problems.extend(csv_problems)
            if arrays is not None and test is not None and test.resample_hz is not None:
                arrays, note = _uniform(data_path.name, arrays, test.resample_hz, problems,
                                        read)
                notes.append(note)
            if arrays is not None and factor > 1:
                from .decimation import decimate_arrays

                out = decimate_arrays(data_path.name, arrays, factor, problems,
                                      test.motion_band_hz if test is not None else None, rig)
                arrays, note = out if out is not None else (None, "")
                notes.append(note)
            if arrays is not None and rig is not None:
                from .spin import spin_column_problems

                problems.extend(spin_column_problems(fname, rig.spin, arrays[3], arrays[0]))

    unknown = unknown_keys(doc, fname, ignored=not strict)
    if motion is not None and arrays is not None and data_path is not None:
        unknown += extra_columns(data_path.name, list(arrays[3]), motion, ignored=not strict)
    if strict and unknown:
        raise CaseError(problems + unknown)
    if problems:  # a likely typo may explain a missing key
        raise CaseError(problems + [u for u in unknown if "did you mean" in u])
    for line in unknown:
        warnings.warn(line, UnknownKey, stacklevel=2)
    if unitless and rig_kind != "spinning":
        for line in _unit_warnings(data_path.name, unitless, arrays, tank, liquid, rig):
            warnings.warn(line, ImplausibleUnit, stacklevel=2)
    assert test is not None and tank is not None and liquid is not None and rig is not None
    assert arrays is not None and data_path is not None
    assert not (pred_present and prediction is None)
    time, disp, force, columns = arrays
    if rig_kind != "spinning":
        slow = sampling_problem(data_path.name, time,
                                lambda: _first_mode_hz(tank, liquid, rig, prediction))
        if slow:
            raise CaseError([slow])
    acc = None  # a lateral record's carriage acceleration, for the checks below
    if rig_kind == "lateral" and motion is None and disp is not None:
        from .bad_samples import clipping
        from .signals import displacement_derivatives

        clipped = clipping("displacement", disp, min_runs=3)
        if clipped is not None:
            raise CaseError([f"{data_path.name}: column `displacement`: {clipped.summary()}: "
                             "the carriage motion is unknown where it is clipped; record it "
                             "within the channel's range"])
        try:
            acc = displacement_derivatives(time, disp)[2]
        except Exception:  # noqa: BLE001 - a record the smoother cannot take: not judged
            acc = None
    if acc is not None and not is_lab_file(data_path):
        for line in _csv_unit_warnings(data_path.name, arrays, rig, prediction, acc):
            warnings.warn(line, ImplausibleUnit, stacklevel=2)
    for arr in (time, disp, force, *columns.values()):
        if arr is not None:
            arr.flags.writeable = False
    case = Case(path=toml_path.resolve(), data_path=data_path.resolve(), test=test, tank=tank,
                liquid=liquid, rig=rig, prediction=prediction, time=time, displacement=disp,
                force=force, columns=columns, notes=tuple(n for n in notes if n))
    if case.motion is not None or acc is not None:
        from .motion_sign import sign_problems

        flipped = sign_problems(case, acceleration=acc)
        if flipped:
            raise CaseError(flipped)
    return case


def _first_mode_hz(tank, liquid, rig, prediction) -> float | None:
    """The tank's first slosh mode [Hz]: ``[prediction]``'s pendulum, else the tank's modal
    analysis (None when it cannot take the tank)."""
    import math

    if prediction is not None:
        return math.sqrt(rig.gravity / prediction.pendulum_length) / (2 * math.pi)
    from analogs.tank import Liquid, predict

    try:
        pred = predict(tank.geometry(), fill=tank.fill_fraction, gravity=rig.gravity,
                       liquid=Liquid(density=liquid.density,
                                     viscosity=liquid.kinematic_viscosity), modes=1)
    except Exception:  # noqa: BLE001 - a tank the prediction cannot take: not judged
        return None
    return pred.modes[0].frequency_hz if pred.modes else None


def _csv_unit_warnings(name: str, arrays: tuple, rig, prediction, acceleration) -> list[str]:
    """What looks wrong about a lateral CSV record's displacement and force, SI by the
    format's definition (:func:`estimate.data.plausible_units.unit_warnings`): a column
    written in mm or a force in lbf or kN. The force is judged against ``[prediction]``'s
    analog and the container when weighed; without ``[prediction]``, only the displacement
    (the tank's modal analysis is not solved for a check at every load)."""
    import math

    time, disp, force, _ = arrays
    columns = ["displacement"]
    rigid, modes = rig.dry_mass or 0.0, []
    if prediction is not None:
        columns.append("force")
        rigid += prediction.fixed_mass
        modes = [(prediction.pendulum_mass, math.sqrt(rig.gravity / prediction.pendulum_length),
                  prediction.damping_ratio)]
    return unit_warnings(name, columns, time, disp, force, rigid_mass=rigid, modes=modes,
                         weighed=rig.dry_mass is not None, csv=True,
                         acceleration=acceleration)


def _unit_warnings(name: str, unitless: dict[str, str], arrays: tuple, tank, liquid, rig
                   ) -> list[str]:
    """What looks wrong about the lab-file columns read with no unit
    (:func:`estimate.data.plausible_units.unit_warnings`), the force judged against the
    tank's predicted analog (:func:`analogs.tank.predict`) and the container when weighed."""
    time, disp, force, _ = arrays
    modes: list[tuple[float, float, float]] = []
    rigid = rig.dry_mass or 0.0
    if "force" in unitless:
        from analogs.tank import Liquid, predict

        try:
            pred = predict(tank.geometry(), fill=tank.fill_fraction, gravity=rig.gravity,
                           liquid=Liquid(density=liquid.density,
                                         viscosity=liquid.kinematic_viscosity), modes=2)
        except Exception:  # noqa: BLE001 - a tank the prediction cannot take: not judged
            unitless = {k: v for k, v in unitless.items() if k != "force"}
        else:
            rigid += pred.fixed_mass.mass
            modes = [(m.mass, m.omega, m.damping_ratio) for m in pred.modes]
    return unit_warnings(name, list(unitless), time, disp, force, rigid_mass=rigid,
                         modes=modes, weighed=rig.dry_mass is not None, channels=unitless)


def _uniform(name: str, arrays: tuple, rate_hz: float, problems: list[str], factor: int
             ) -> tuple[tuple | None, str]:
    """``arrays`` (time, displacement, force, columns) on a uniform time base at about
    ``rate_hz`` (:func:`estimate.data.timebase.uniform_record`), and what was done
    (``factor``: the decimation that follows, which lets the grid hold as many more
    samples)."""
    from .budget import max_samples
    from .timebase import uniform_record

    time, disp, force, columns = arrays
    named = {"displacement": disp, "force": force, **columns}
    record = uniform_record(name, time, {k: v for k, v in named.items() if v is not None},
                            rate_hz, problems, max_samples=max_samples() * factor)
    if record is None:
        return None, ""
    out = record.columns
    return ((record.time, out.get("displacement"), out.get("force"),
             {k: out[k] for k in columns}), record.note)
