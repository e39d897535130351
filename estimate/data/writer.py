"""``write_case``: a case file (TOML) and its CSV written together, validated before they
are moved into place."""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .case import (
    DRY_MASS_ESTIMATE,
    LIMIT_UNITS,
    SHAPE_KEYS,
    SPINNING_CHANNELS,
    Case,
    Liquid,
    Prediction,
    Rig,
    Tank,
    TestInfo,
)
from .reader import load_case

__all__ = ["write_case"]


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):  # a count ([test] decimate) stays a TOML integer
        return str(value)
    if isinstance(value, float):
        number = float(value)
        if not math.isfinite(number):
            raise ValueError(f"cannot write a non-finite number {value!r} to a case file")
        return repr(number)
    if isinstance(value, str):
        # JSON string escapes are valid TOML basic-string escapes.
        return json.dumps(value, ensure_ascii=False)
    raise TypeError(f"cannot write {type(value).__name__} `{value!r}` to a case file")


def _toml_text(test: TestInfo, tank: Tank, liquid: Liquid, rig: Rig,
               prediction: Prediction | None, comment: str) -> str:
    out: list[str] = []
    for line in comment.splitlines():
        out.append(f"# {line}".rstrip())
    if out:
        out.append("")

    def table(name: str, rows: list[tuple[str, Any, str]]) -> None:
        out.append(f"[{name}]")
        width = max((len(k) + 3 + len(_toml_value(v)) for k, v, n in rows if n), default=0)
        for key, value, note in rows:
            text = f"{key} = {_toml_value(value)}"
            out.append(f"{text:<{width}}   # {note}" if note else text)
        out.append("")

    rows: list[tuple[str, Any, str]] = [
        ("id", test.id, ""), ("rig", test.rig, ""),
        ("data", test.data, "CSV path relative to this file"),
        ("excitation", test.excitation, ""),
    ]
    if test.note is not None:
        rows.append(("note", test.note, ""))
    if test.starts_at_rest is not None:
        rows.append(("starts_at_rest", test.starts_at_rest, "tank and carriage at rest at t[0]"))
    if test.initial_state is not None:
        rows.append(("initial_state", test.initial_state, "the liquid at t[0]"))
    if test.resample_hz is not None:
        rows.append(("resample_hz", test.resample_hz, "Hz, a uniform time base for the record"))
    if test.motion_band_hz is not None:
        rows.append(("motion_band_hz", test.motion_band_hz, "Hz, top of the carriage motion"))
    if test.decimate is not None:
        rows.append(("decimate", test.decimate, "fit every k-th sample, after an anti-alias "
                                                "low-pass"))
    table("test", rows)
    sizes = {"radius": "m", "length": "m, cylinder height or rectangular along the motion",
             "cylinder_length": "m, capsule straight section", "width": "m, across the motion",
             "height": "m, inside height"}
    table("tank", [("shape", tank.shape, "")]
          + [(k, getattr(tank, k), note) for k, note in sizes.items() if k in SHAPE_KEYS[tank.shape]]
          + [("fill_fraction", tank.fill_fraction, "liquid depth / tank height"),
             ("diaphragm", tank.diaphragm, "")])
    table("liquid", [("density", liquid.density, "kg/m^3"),
                     ("kinematic_viscosity", liquid.kinematic_viscosity, "m^2/s")])
    dry = (rig.dry_mass, "kg moving with the tank, seen by the transducer") \
        if rig.dry_mass is not None else (DRY_MASS_ESTIMATE, "not weighed: estimated")
    table("rig", [("dry_mass", *dry),
                  ("gravity", rig.gravity, "m/s^2")])
    if rig.spin is not None:
        sp = rig.spin
        table("rig.spin", [("rate", sp.rate, "rad/s, table spin rate"),
                           ("radius", sp.radius, "m, tank origin from the spin axis"),
                           ("nutation_angle", sp.nutation_angle, "rad, cone half-angle"),
                           ("nutation_frequency", sp.nutation_frequency, "Hz, coning frequency"),
                           ("height", sp.height, "m, tank origin above the nutation pivot"),
                           ("tank_axis", sp.tank_axis, ""),
                           ("gravity_on", sp.gravity_on, "")] + _spin_motion_rows(sp))
    if rig.motion is not None:
        units = {"x": "m", "y": "m", "z": "m", "roll": "rad", "pitch": "rad", "yaw": "rad"}
        table("rig.motion", [(k, v, f"CSV column, {units[k]}") for k, v in rig.motion.columns.items()])
    if rig.transducer is not None:
        tr = rig.transducer
        table("rig.transducer", [(k, getattr(tr, k), "m, reference point in tank axes")
                                 for k in ("x", "y", "z")]
              + [(k, getattr(tr, k), "rad, turn of its axes from the tank's (z-y-x)")
                 for k in ("roll", "pitch", "yaw")])
    if rig.crank is not None:
        table("rig.crank", [("radius", rig.crank.radius, "m"),
                            ("rod_length", rig.crank.rod_length, "m"),
                            ("frequency", rig.crank.frequency, "Hz, nominal drive")])
    if rig.limits is not None:
        table("rig.limits", [(k, getattr(rig.limits, k), unit) for k, unit in LIMIT_UNITS.items()
                             if getattr(rig.limits, k) is not None])
    if prediction is not None:
        table("prediction", [("pendulum_mass", prediction.pendulum_mass, "kg"),
                             ("pendulum_length", prediction.pendulum_length, "m"),
                             ("fixed_mass", prediction.fixed_mass, "kg"),
                             ("damping_ratio", prediction.damping_ratio, "fraction of critical")])
    return "\n".join(out).rstrip("\n") + "\n"


def _spin_motion_rows(spin) -> list[tuple[str, Any, str]]:
    """The measured-motion columns and schedules of ``[rig.spin]`` that are set."""
    notes = {"spin_angle": "CSV column, rad", "spin_rate": "CSV column, rad/s",
             "nutation_phase": "CSV column, rad", "cone_angle": "CSV column, rad"}
    rows: list[tuple[str, Any, str]] = [(k, v, notes[k]) for k, v in spin.columns.items()]
    if spin.spin_up:
        rows.append(("spin_up", spin.spin_up, "s, spin-up from rest"))
    if spin.nutation_ramp:
        rows.append(("nutation_ramp", spin.nutation_ramp, "s, cone-angle ramp"))
    if spin.nutation_start is not None:
        rows.append(("nutation_start", spin.nutation_start, "s after t[0]"))
    return rows


def _csv_text(time: NDArray[np.float64], displacement: NDArray[np.float64] | None,
              force: NDArray[np.float64] | None,
              channels: Mapping[str, NDArray[np.float64]] | None = None) -> str:
    if channels is not None:
        cols = [time, *channels.values()]
        header = ",".join(["time", *channels])
    else:
        assert force is not None
        cols = [time] if displacement is None else [time, displacement]
        cols.append(force)
        header = "time,force" if displacement is None else "time,displacement,force"
    body = np.column_stack(cols)
    lines = [header]
    lines.extend(",".join(format(float(v), ".12g") for v in row) for row in body)
    return "\n".join(lines) + "\n"


def write_case(path: str | os.PathLike[str], *, test: TestInfo, tank: Tank, liquid: Liquid,
               rig: Rig, time: ArrayLike, force: ArrayLike | None = None,
               displacement: ArrayLike | None = None, prediction: Prediction | None = None,
               channels: Mapping[str, ArrayLike] | None = None,
               comment: str = "", overwrite: bool = False) -> Case:
    """Write a case file (TOML) and its CSV, then load them back.

    The CSV goes to ``test.data`` relative to the TOML file. Both files are first written to a
    temporary folder and validated with :func:`load_case`; only a valid case is moved into
    place, so an invalid one leaves no files behind.

    Parameters
    ----------
    path : str or path-like
        The TOML file to write.
    test, tank, liquid, rig, prediction
        The tables to write (``prediction`` optional).
    time : array_like
        Sample times [s].
    force : array_like, optional
        Lateral force [N] (lateral rig; required there).
    displacement : array_like, optional
        Carriage displacement [m]; omit for ``excitation = "crank"`` without a measured
        displacement.
    channels : mapping of str to array_like, optional
        Spinning rig (required there): the six channels of :data:`SPINNING_CHANNELS`
        (N, N m) and any extra columns, written in this order after ``time``. A six-axis
        record (``rig.motion`` set, required there): its motion columns and any subset of
        the six channels.
    comment : str, optional
        Text written as ``#`` comment lines at the top of the TOML file.
    overwrite : bool, default False
        Replace existing files. When False and either file exists, nothing is written.

    Returns
    -------
    Case
        The case as loaded back from the written files.

    Raises
    ------
    FileExistsError
        If a target file exists and ``overwrite`` is False.
    CaseError
        If the written case does not validate (no files are left in place).

    Examples
    --------
    >>> import numpy as np
    >>> from estimate.data.case import TestInfo, Tank, Liquid, Rig
    >>> from estimate.data import write_case
    >>> t = np.arange(100) * 0.01
    >>> case = write_case(
    ...     "/tmp/demo.toml", overwrite=True,
    ...     test=TestInfo(id="demo", rig="lateral", data="demo.csv", excitation="measured"),
    ...     tank=Tank(shape="sphere", radius=0.1016, fill_fraction=0.6, diaphragm=False),
    ...     liquid=Liquid(density=998.2, kinematic_viscosity=1.004e-6),
    ...     rig=Rig(dry_mass=1.2, gravity=9.80665),
    ...     time=t, displacement=0.005 * np.sin(2 * np.pi * 2 * t),
    ...     force=np.sin(2 * np.pi * 2 * t))                                # doctest: +SKIP
    """
    toml_path = Path(path)
    csv_rel = Path(test.data)
    csv_path = csv_rel if csv_rel.is_absolute() else toml_path.parent / csv_rel
    if not overwrite:
        existing = [str(p) for p in (toml_path, csv_path) if p.exists()]
        if existing:
            raise FileExistsError(f"refusing to overwrite existing file(s) {', '.join(existing)}; "
                                  "pass `overwrite=True` to replace them")
    t = np.asarray(time, dtype=float)
    if test.rig == "spinning" or rig.motion is not None:
        if channels is None or force is not None or displacement is not None:
            what = ("a spinning-rig case takes `channels` (time series of " if test.rig == "spinning"
                    else "a six-axis record (`rig.motion`) takes `channels` (time series of its "
                    "motion columns and any of ")
            raise ValueError(what + ", ".join(SPINNING_CHANNELS) + "), not `force` or "
                             "`displacement`")
        ch = {str(k): np.asarray(v, dtype=float) for k, v in channels.items()}
        bad = {k: v.shape for k, v in ch.items() if v.shape != t.shape}
        if t.ndim != 1 or bad:
            raise ValueError(f"expected 1-D `time` and channels of its length {t.shape}, found "
                             + ", ".join(f"`{k}` {v}" for k, v in bad.items()))
        toml_text = _toml_text(test, tank, liquid, rig, prediction, comment)
        csv_text = _csv_text(t, None, None, ch)
    else:
        if force is None or channels is not None:
            raise ValueError("a lateral-rig case takes `force` (and `displacement`), "
                             "not `channels`")
        f = np.asarray(force, dtype=float)
        d = None if displacement is None else np.asarray(displacement, dtype=float)
        if t.ndim != 1 or f.shape != t.shape or (d is not None and d.shape != t.shape):
            raise ValueError(f"expected 1-D `time`, `force` (and `displacement`) of equal "
                             f"length, found shapes {t.shape}, {f.shape}"
                             + ("" if d is None else f", {d.shape}"))
        toml_text = _toml_text(test, tank, liquid, rig, prediction, comment)
        csv_text = _csv_text(t, d, f)

    toml_path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=toml_path.parent, prefix=".case-") as tmp:
        tmp_toml = Path(tmp) / toml_path.name
        tmp_csv = Path(tmp) / (csv_rel.name if csv_rel.is_absolute() else csv_rel)
        tmp_csv.parent.mkdir(parents=True, exist_ok=True)
        tmp_toml.write_text(toml_text, encoding="utf-8")
        tmp_csv.write_text(csv_text, encoding="utf-8")
        if csv_rel.is_absolute():
            # load_case reads the absolute path; validate the temporary copy instead.
            tmp_toml.write_text(toml_text.replace(_toml_value(test.data),
                                                  _toml_value(tmp_csv.name)), encoding="utf-8")
        load_case(tmp_toml)  # raises CaseError; the temporary folder is then removed
        csv_path.parent.mkdir(parents=True, exist_ok=True)
        shutil.move(str(tmp_csv), str(csv_path))
        tmp_toml.write_text(toml_text, encoding="utf-8")
        shutil.move(str(tmp_toml), str(toml_path))
    return load_case(toml_path)
