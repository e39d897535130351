"""Six-axis records of a tank moved in 3-D (:class:`analogs.MotionRig`): the ``[rig.motion]``
and ``[rig.transducer]`` tables of a case, the columns of its CSV, the rig's inputs from the
measured motion, and the fit's notes on them; the check that each force channel has the sign
of mass times acceleration is in :mod:`estimate.data.motion_sign`.

The case-file keys are described in :mod:`estimate.data.case` ("Six-axis records of any
tank motion").
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from analogs.motion_rig import MOTION_AXES, ROTATIONS, TRANSLATIONS

from .case import SPINNING_CHANNELS, Case, CaseError, Motion, Transducer

__all__ = ["CHANNELS", "EDGE_PERIODS", "axis_derivatives", "edge_weights", "extra_columns",
           "input_note", "moments_note", "motion_columns", "motion_excitation",
           "motion_header_problems", "motion_of", "motion_values", "read_motion"]

#: The channels a six-axis record may hold (any non-empty subset), N and N m.
CHANNELS: tuple[str, ...] = SPINNING_CHANNELS
#: Largest transducer angle accepted [rad]: a number beyond a turn is a value in degrees.
_MAX_ANGLE = 2 * math.pi
_UNITS = {a: "m" for a in TRANSLATIONS} | {a: "rad" for a in ROTATIONS}
_MEANING = {"x": "the tank origin's travel along the lab x axis", "y": "its travel along lab y",
            "z": "its vertical travel", "roll": "the tank's roll angle",
            "pitch": "the tank's pitch angle", "yaw": "the tank's yaw angle"}


# -- the case file's tables ------------------------------------------------------------------

def read_motion(ck, doc: Mapping[str, Any], rig_kind: str | None, excitation: str | None
                ) -> tuple[bool, Motion | None, Transducer | None]:
    """``[rig.motion]`` and ``[rig.transducer]`` of ``doc``: (both valid, motion,
    transducer); problems go to the checker ``ck`` (:class:`estimate.data._checker.Checker`)."""
    rig = doc.get("rig")
    has_motion = isinstance(rig, Mapping) and "motion" in rig
    has_transducer = isinstance(rig, Mapping) and "transducer" in rig
    if not has_motion:
        if has_transducer:
            ck.add("[rig.transducer]", "applies to six-axis records of a tank moved in 3-D: "
                   "name the CSV columns of the measured motion in a `[rig.motion]` table "
                   '(e.g. `x = "x"`)')
            return False, None, None
        return True, None, None
    ok = True
    if rig_kind == "spinning":
        ck.add("[rig.motion]", 'a spinning-rig case (`rig = "spinning"`) gives its motion in '
               "`[rig.spin]`; `[rig.motion]` belongs to `rig = \"lateral\"` cases of a tank "
               "moved in 3-D")
        ok = False
    if excitation == "crank":
        ck.add("[rig.motion]", 'names measured motion columns: it needs `[test] excitation = '
               '"measured"`, found "crank"')
        ok = False
    t = ck.table(doc, "rig.motion", required=True)
    if t is None:
        return False, None, None
    columns: dict[str, str] = {}
    for axis in MOTION_AXES:
        if axis not in t:
            continue
        value = t[axis]
        if not isinstance(value, str) or not value.strip():
            from ._checker import type_name

            found = 'an empty string ""' if isinstance(value, str) else \
                f"{type_name(value)} `{value!r}`"
            ck.add(f"[rig.motion] {axis}", f"expected the name of the CSV column holding "
                   f"{_MEANING[axis]} ({_UNITS[axis]}), e.g. `{axis} = \"{axis}\"`, found {found}")
            ok = False
            continue
        columns[axis] = value.strip()
    if ok and not columns:
        ck.add("[rig.motion]", "names no motion column: expected at least one of "
               + ", ".join(f"`{a}`" for a in MOTION_AXES) + ' (e.g. `x = "x"`)')
        ok = False
    used: dict[str, list[str]] = {}
    for axis, col in columns.items():
        used.setdefault(col, []).append(axis)
    for col, axes in used.items():
        if len(axes) > 1:
            ck.add(f"[rig.motion] {axes[1]}", f"the column `{col}` is also `{axes[0]}`: each "
                   "axis needs its own column")
            ok = False
        if col == "time" or col in CHANNELS:
            what = "time" if col == "time" else "force/torque channel"
            ck.add(f"[rig.motion] {axes[0]}", f"`{col}` is the {what} column, not a motion column")
            ok = False
    transducer = None
    if has_transducer:
        transducer, tok = _read_transducer(ck, doc)
        ok = ok and tok
    return ok, Motion(**columns) if ok else None, transducer if ok else None


def _read_transducer(ck, doc) -> tuple[Transducer | None, bool]:
    t = ck.table(doc, "rig.transducer", required=True)
    if t is None:
        return None, False
    values: dict[str, float] = {}
    ok = True
    for key in TRANSLATIONS:
        if key in t:
            v = ck.number(t, "rig.transducer", key, unit="m")
            ok = ok and v is not None
            values[key] = v
    for key in ROTATIONS:
        if key not in t:
            continue
        v = ck.number(t, "rig.transducer", key, unit="rad")
        if v is not None and abs(v) > _MAX_ANGLE:
            ck.add(f"[rig.transducer] {key}", f"expected an angle in rad of magnitude up to 2 pi, "
                   f"found {t[key]!r} (degrees? 180 deg is 3.141592653589793 rad)")
            v = None
        ok = ok and v is not None
        values[key] = v
    return (Transducer(**values) if ok else None), ok


def motion_columns(doc: Mapping[str, Any]) -> dict[str, str] | None:
    """The motion columns ``[rig.motion]`` names (the valid ones, by axis), for the CSV
    reader even when the tables have problems; ``None`` without a ``[rig.motion]`` table."""
    rig = doc.get("rig")
    if not isinstance(rig, Mapping) or not isinstance(rig.get("motion"), Mapping):
        return None
    table = rig["motion"]
    return {a: table[a].strip() for a in MOTION_AXES
            if a in table and isinstance(table[a], str) and table[a].strip()}


# -- the CSV --------------------------------------------------------------------------------

def motion_header_problems(name: str, header_line: int, header: Sequence[str],
                           motion: Mapping[str, str]) -> list[str]:
    """Problems of a six-axis record's CSV header: ``time`` first, every motion column of
    ``motion`` (by axis) present, at least one force/torque channel, no repeated column."""
    names = [c.strip() for c in header]
    found = []
    if not names or names[0] != "time":
        found.append(f"first column `{names[0] if names else ''}` instead of `time`")
    for axis, col in motion.items():
        if col not in names:
            near = difflib.get_close_matches(col, names, n=1)
            found.append(f"no column `{col}` (`[rig.motion] {axis}`"
                         + (f"; did you mean `{near[0]}`?)" if near else ")"))
    if not any(c in names for c in CHANNELS):
        near = [m for c in names for m in difflib.get_close_matches(c, CHANNELS, n=1)]
        found.append("no force/torque channel (expected one or more of "
                     + ", ".join(f"`{c}`" for c in CHANNELS) + ")"
                     + (f"; did you mean `{near[0]}`?" if near else ""))
    repeated = sorted({c for c in names if names.count(c) > 1})
    if repeated:
        found.append("repeated column(s) " + ", ".join(f"`{c}`" for c in repeated))
    if not found:
        return []
    return [f"{name}: header (line {header_line}): expected `time`, the motion columns of "
            f"`[rig.motion]` ({', '.join(f'`{c}`' for c in motion.values())}) and force/torque "
            f"channels for a six-axis record, found `{','.join(header)}` ({'; '.join(found)})"]


def extra_columns(name: str, columns: Sequence[str], motion: Mapping[str, str], *,
                  ignored: bool) -> list[str]:
    """One line per column of a six-axis record that is neither a channel nor a motion
    column (a typo, or a channel the fit does not use), with the nearest known name;
    ``ignored``: say that it is ignored (a warning) rather than refused."""
    known = [*CHANNELS, *motion.values()]
    out = []
    for col in columns:
        if col in known or col == "time":
            continue
        near = difflib.get_close_matches(col, known, n=1)
        hint = f"did you mean `{near[0]}`?" if near else (
            "expected a channel (" + ", ".join(f"`{c}`" for c in CHANNELS) + ") or a motion "
            "column named in `[rig.motion]`")
        out.append(f"{name}: unknown column `{col}`{' (ignored)' if ignored else ''}; {hint}")
    return out


# -- the rig's inputs -----------------------------------------------------------------------

#: A record's end counts as a rest when the axis stays within this many of its noise's
#: standard deviations of its value there for :data:`REST_SECONDS` or longer.
REST_SIGMAS = 5.0
REST_SECONDS = 0.2
#: Length [s] of the rest put before (after) an axis that starts (ends) at rest, longer
#: than the response of the derivative filter (an eighth-order Butterworth at 4 Hz or
#: above rings for well under a second).
_REST_PAD_SECONDS = 2.0


def _noise_std(y: NDArray[np.float64]) -> float:
    """The white noise of a sampled motion: the median absolute second difference (the
    motion itself hardly changes in two samples) over 0.6745 sqrt(6)."""
    d2 = np.diff(y, 2)
    return float(np.median(np.abs(d2 - np.median(d2))) / 0.6745 / math.sqrt(6.0))


def _rest_run(y: NDArray[np.float64], tol: float) -> int:
    """Samples from the start during which ``y`` stays within ``tol`` of its start (the
    median of its first 10 samples)."""
    away = np.flatnonzero(np.abs(y - np.median(y[:10])) > tol)
    return int(away[0]) if away.size else y.size


def axis_derivatives(time: NDArray[np.float64], values: NDArray[np.float64], *,
                     motion_band_hz: float | None = None, starts_at_rest: bool | None = None
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """One measured axis (m or rad) smoothed without phase lag, with its rate and
    acceleration: :func:`estimate.data.signals.displacement_derivatives` (the lateral
    carriage's filter) of the record with its rests continued.

    A rig test starts and often ends with the tank at rest; the filter's end model (a line
    and a sinusoid fitted to the first and last seconds) would continue the ramp-in of a
    drive as an oscillation before the record and put a spurious acceleration into its first
    half second (0.23 rad/s^2 RMS on a 5 deg, 0.95 Hz pitch ramped in from rest, 7 % of its
    amplitude). So an end at rest (the axis within :data:`REST_SIGMAS` of its noise for
    :data:`REST_SECONDS` or more; ``starts_at_rest=False`` says the record does not start at
    rest) is continued by its mean value for 2 s before filtering, and the filter's cutoff
    is read from the record itself."""
    from .signals import displacement_derivatives, motion_band

    t = np.asarray(time, float)
    y = np.asarray(values, float)
    band = motion_band_hz or motion_band(t, y)
    tol = REST_SIGMAS * max(_noise_std(y), 1e-15)
    step = float(np.median(np.diff(t)))
    n_rest, n_pad = int(math.ceil(REST_SECONDS / step)), int(math.ceil(_REST_PAD_SECONDS / step))
    parts, lead = [y], 0
    if starts_at_rest is not False:
        run = _rest_run(y, tol)
        if n_rest <= run < y.size:
            parts.insert(0, np.full(n_pad, float(np.mean(y[:run]))))
            lead = n_pad
    run = _rest_run(y[::-1], tol)
    if n_rest <= run < y.size:
        parts.append(np.full(n_pad, float(np.mean(y[y.size - run:]))))
    ext = np.concatenate(parts)
    te = t[0] + (np.arange(ext.size) - lead) * step
    out = displacement_derivatives(te, ext, motion_band_hz=band)
    return tuple(v[lead:lead + y.size] for v in out)  # type: ignore[return-value]


def motion_values(case: Case) -> dict[str, tuple[NDArray[np.float64], ...]]:
    """Each measured axis of ``case`` smoothed without phase lag with its rate and
    acceleration (:func:`axis_derivatives`), by axis name (m or rad)."""
    motion = motion_of(case)
    return {axis: axis_derivatives(case.time, case.channels[col],
                                   motion_band_hz=case.test.motion_band_hz,
                                   starts_at_rest=case.test.starts_at_rest)
            for axis, col in motion.columns.items()}


def motion_excitation(case: Case, values: Mapping[str, tuple] | None = None):
    """The input signals of :class:`analogs.MotionRig` (``axes = case.motion.axes``) from
    the measured motion of ``case`` (:func:`motion_values` unless ``values`` gives them)."""
    from derive import Sampled

    values = motion_values(case) if values is None else values
    rows = [v for axis in motion_of(case).axes for v in values[axis]]
    return Sampled(case.time, np.vstack(rows))


def motion_of(case: Case) -> Motion:
    """The ``[rig.motion]`` table of ``case``; raises :class:`CaseError` for a case that is
    not a six-axis record."""
    if case.motion is None:
        raise CaseError([f"{case.path.name}: not a six-axis record of a tank moved in 3-D "
                         "(no `[rig.motion]` table)"])
    return case.motion


#: Samples within this many force-filter periods (``1 / cutoff``) of a six-axis record's
#: ends are left out of a filtered-input fit: there the zero-phase filter runs on its end
#: model (a line and a sinusoid), which cannot continue a force of several frequencies (a
#: drive in x, y and pitch with the slosh mode): the first and last 0.1 s of an 8 s record
#: at 10 Hz held 0.1-0.65 N of error against a noise of 0.01 N, and put its residual at 3.5
#: times its noise figure.
EDGE_PERIODS = 2.0


def edge_weights(case: Case, cutoff_hz: float | None) -> NDArray[np.float64] | None:
    """Sample weights of a six-axis record fitted with the force low-passed at
    ``cutoff_hz``: 0 within :data:`EDGE_PERIODS` filter periods of either end, 1 elsewhere;
    ``None`` (all samples) without a filter or for other records."""
    if case.motion is None or cutoff_hz is None:
        return None
    t = np.asarray(case.time, float)
    edge = EDGE_PERIODS / cutoff_hz
    return ((t - t[0] >= edge) & (t[-1] - t >= edge)).astype(float)


def input_note(mode: str, cutoff_hz: float | None) -> str:
    """The fit's note on how a six-axis record's motion and channels enter it (``mode``:
    the problem's input mode, ``cutoff_hz``: its force filter)."""
    how = ("smoothed without phase lag and differentiated twice, then taken as exact "
           "(the filtered input"
           + ("; the estimated input is the lateral carriage's" if mode == "estimated" else "")
           + ")")
    channels = ("the channels unfiltered" if cutoff_hz is None else
                f"the channels low-passed at {cutoff_hz:g} Hz, their first and last "
                f"{EDGE_PERIODS / cutoff_hz:.2g} s left out")
    return (f"six-axis record: each measured motion axis {how}; {channels}; noise of the "
            "measured translations inside the slosh band drives the analog as if it were "
            "motion, which biases the frequency slightly (0.05 % at 2e-5 m)")


#: Local parameter names that place the analog's masses (what a six-axis record's moments
#: determine and a lateral force cannot).
_PLACEMENT = ("height", "hinge_height", "inertia", "axial_inertia")


def moments_note(model, estimated: Sequence[str], values: Mapping[str, float]) -> str | None:
    """The fit's note on the heights and inertias of ``model``'s analog: which are
    ``estimated`` from a six-axis record (its torques, or the forces of a rotating tank) and
    which enter none of its channels and keep their ``values`` (the tank module's, or the
    user's); ``None`` for an analog without them."""
    placing = [p for p in model.parameters
               if not p.name.startswith(f"{model.rig.name}.") and p.local_name in _PLACEMENT]
    if not placing:
        return None
    est = [p.name for p in placing if p.name in estimated]
    kept = [p for p in placing if p.name not in estimated]
    parts = []
    if est:
        parts.append(", ".join(f"`{n}`" for n in est) + " estimated from the record's channels "
                     "(the identifiability check says whether they are determined)")
    if kept:
        parts.append(", ".join(
            f"`{p.name}` = {values[p.name]:.4g} {p.unit}" if p.name in values else f"`{p.name}`"
            for p in kept) + (" enters" if len(kept) == 1 else " enter")
            + " none of its channels: kept from the tank module (or as given), not determined "
              "by the data")
    return "six-axis record: " + "; ".join(parts)
