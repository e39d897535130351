"""Validation of the TOML tables of a case file: every problem is collected, none raised."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from ._checker import Checker, range_problem, type_name
from .case import (
    DRY_MASS_ESTIMATE,
    KNOWN_EXCITATIONS,
    KNOWN_INITIAL_STATES,
    KNOWN_RIGS,
    KNOWN_SHAPES,
    SHAPE_KEYS,
    SPIN_COLUMN_KEYS,
    TANK_AXES,
    Crank,
    Liquid,
    Prediction,
    Rig,
    Spin,
    Tank,
    TestInfo,
)

__all__ = ["Checker", "range_problem", "read_tables", "test_kind"]


def _read_test(ck: Checker, doc: Mapping[str, Any]) -> TestInfo | None:
    t = ck.table(doc, "test", required=True)
    if t is None:
        return None
    test_id = ck.string(t, "test", "id")
    rig = ck.string(t, "test", "rig", choices=KNOWN_RIGS)
    data = ck.string(t, "test", "data")
    spinning = rig == "spinning"
    excitation = ck.string(t, "test", "excitation",
                           choices=("spin",) if spinning else ("measured", "crank"),
                           required=not spinning)
    if spinning and "excitation" not in t:
        excitation = "spin"  # the spinning rig's motion comes from `[rig.spin]`
    note = ck.string(t, "test", "note", required=False)
    at_rest = ck.boolean(t, "test", "starts_at_rest") if "starts_at_rest" in t else None
    bad_rest = "starts_at_rest" in t and at_rest is None
    initial = ck.string(t, "test", "initial_state", choices=KNOWN_INITIAL_STATES, required=False)
    bad_rest = bad_rest or ("initial_state" in t and initial is None)
    rates = {}
    for key in ("resample_hz", "motion_band_hz"):
        if key in t:
            rates[key] = ck.number(t, "test", key, unit="Hz", positive=True)
            bad_rest = bad_rest or rates[key] is None
    if "decimate" in t:
        factor = t["decimate"]
        if isinstance(factor, bool) or not isinstance(factor, int) or factor < 1:
            ck.add("[test] decimate", "expected an integer >= 1 (keep every k-th sample after "
                   f"an anti-alias low-pass), found {type_name(factor)} `{factor!r}`")
            bad_rest = True
        else:
            rates["decimate"] = factor
    if data is not None and not data.strip():
        ck.add("[test] data", 'expected a CSV path, found an empty string ""')
        data = None
    if None in (test_id, rig, data, excitation) or bad_rest:
        return None
    assert test_id is not None and rig is not None and data is not None
    assert excitation is not None
    return TestInfo(id=test_id, rig=rig, data=data, excitation=excitation, note=note,
                    starts_at_rest=at_rest, initial_state=initial, **rates)


def _read_tank(ck: Checker, doc: Mapping[str, Any]) -> Tank | None:
    t = ck.table(doc, "tank", required=True)
    if t is None:
        return None
    shape = ck.string(t, "tank", "shape", choices=KNOWN_SHAPES)
    fill = ck.number(t, "tank", "fill_fraction", unit="-", open_unit_interval=True)
    diaphragm = ck.boolean(t, "tank", "diaphragm")
    if shape is None:  # the sizes given are still checked as lengths
        # `key in t`, not `set(t)`: iterating the table would hide its unknown keys
        for key in sorted(k for k in _ALL_SIZE_KEYS if k in t):
            ck.number(t, "tank", key, unit="m", nonnegative=True)
        return None
    needed = SHAPE_KEYS[shape]
    sizes: dict[str, float | None] = {}
    for key in needed:
        if key not in t:
            ck.add(f"[tank] {key}", f"missing key (expected {_SIZE_MEANING[key]} in m for "
                   f'`shape = "{shape}"`{_SIZE_HINT.get((shape, key), "")})')
            sizes[key] = None
            continue
        sizes[key] = ck.number(t, "tank", key, unit="m", positive=key != "cylinder_length",
                               nonnegative=key == "cylinder_length")
    for key in sorted(_ALL_SIZE_KEYS - set(needed)):
        if key in t:
            users = [s for s, keys in SHAPE_KEYS.items() if key in keys]
            ck.add(f"[tank] {key}", f'not a size of a {shape} (expected only '
                   + ", ".join(f"`{k}`" for k in needed) + f' for `shape = "{shape}"`; `{key}` '
                   f'belongs to {_and(users)} tanks)' + _MISPLACED_HINT.get((shape, key), ""))
            sizes[key] = None
    if fill is None or diaphragm is None or any(v is None for v in sizes.values()):
        return None
    return Tank(shape=shape, radius=sizes.get("radius"), fill_fraction=fill, diaphragm=diaphragm,
                length=sizes.get("length"), cylinder_length=sizes.get("cylinder_length"),
                width=sizes.get("width"), height=sizes.get("height"))


_SIZE_MEANING = {"radius": "the inside radius", "length": "the inside length",
                 "cylinder_length": "the length of the straight section between the domes",
                 "width": "the inside width across the motion", "height": "the inside height"}
_SIZE_HINT = {("cylinder", "length"): ": the inside height, which the fill fraction is "
                                      "measured against (no longer assumed equal to the "
                                      "diameter)",
              ("rectangular", "length"): ": along the motion",
              ("capsule", "cylinder_length"): "; 0 for a sphere, the inside height is "
                                              "`cylinder_length + 2 radius`"}
_MISPLACED_HINT = {("capsule", "length"): "; a capsule's straight section is "
                                          "`cylinder_length` (inside height "
                                          "`cylinder_length + 2 radius`)"}
_ALL_SIZE_KEYS = {k for keys in SHAPE_KEYS.values() for k in keys}


def _and(words: list[str]) -> str:
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]


def _read_liquid(ck: Checker, doc: Mapping[str, Any]) -> Liquid | None:
    t = ck.table(doc, "liquid", required=True)
    if t is None:
        return None
    density = ck.number(t, "liquid", "density", unit="kg/m^3", positive=True)
    nu = ck.number(t, "liquid", "kinematic_viscosity", unit="m^2/s", positive=True)
    if density is None or nu is None:
        return None
    return Liquid(density=density, kinematic_viscosity=nu)


def _read_crank(ck: Checker, doc: Mapping[str, Any], *, required: bool) -> tuple[bool, Crank | None]:
    """Return (table present, crank or None)."""
    rig = doc.get("rig")
    present = isinstance(rig, Mapping) and "crank" in rig
    if not present:
        if required:
            ck.add("[rig.crank]", 'missing table (expected `[rig.crank]` with radius, rod_length '
                   'and frequency because `[test] excitation = "crank"`)')
        return False, None
    t = ck.table(doc, "rig.crank", required=True)
    if t is None:
        return True, None
    radius = ck.number(t, "rig.crank", "radius", unit="m", positive=True)
    rod = ck.number(t, "rig.crank", "rod_length", unit="m", positive=True)
    freq = ck.number(t, "rig.crank", "frequency", unit="Hz", positive=True)
    if radius is not None and rod is not None and not rod > radius:
        ck.add("[rig.crank] rod_length",
               f"expected a rod longer than the crank radius ({radius!r} m), found {rod!r} m")
        rod = None
    if radius is None or rod is None or freq is None:
        return True, None
    return True, Crank(radius=radius, rod_length=rod, frequency=freq)


def _read_spin(ck: Checker, doc: Mapping[str, Any], *, required: bool) -> tuple[bool, Spin | None]:
    """Return (table present, spin or None)."""
    rig = doc.get("rig")
    present = isinstance(rig, Mapping) and "spin" in rig
    if not present:
        if required:
            ck.add("[rig.spin]", 'missing table (expected `[rig.spin]` with rate, radius, '
                   'nutation_angle and nutation_frequency because `[test] rig = "spinning"`)')
        return False, None
    t = ck.table(doc, "rig.spin", required=True)
    if t is None:
        return True, None
    rate = ck.number(t, "rig.spin", "rate", unit="rad/s")
    radius = ck.number(t, "rig.spin", "radius", unit="m", nonnegative=True)
    angle = ck.number(t, "rig.spin", "nutation_angle", unit="rad", nonnegative=True)
    if angle is not None and not angle < math.pi / 2:
        ck.add("[rig.spin] nutation_angle",
               f"expected a cone half-angle below pi/2 rad, found {angle!r} rad")
        angle = None
    freq = ck.number(t, "rig.spin", "nutation_frequency", unit="Hz")
    height = ck.number(t, "rig.spin", "height", unit="m") if "height" in t else 0.0
    axis = ck.string(t, "rig.spin", "tank_axis", choices=TANK_AXES, required=False)
    gravity_on = ck.boolean(t, "rig.spin", "gravity_on") if "gravity_on" in t else True
    motion, motion_ok = _read_spin_motion(ck, t)
    if None in (rate, radius, angle, freq, height, gravity_on) or ("tank_axis" in t and axis is None) \
            or not motion_ok:
        return True, None
    assert rate is not None and radius is not None and angle is not None and freq is not None
    assert height is not None and gravity_on is not None
    return True, Spin(rate=rate, radius=radius, nutation_angle=angle, nutation_frequency=freq,
                      height=height, tank_axis=axis or "spin", gravity_on=gravity_on, **motion)


def _read_spin_motion(ck: Checker, t: Mapping[str, Any]) -> tuple[dict[str, Any], bool]:
    """The measured-motion columns and schedules of ``[rig.spin]``: (values, all valid)."""
    out: dict[str, Any] = {}
    ok = True
    for key in SPIN_COLUMN_KEYS:
        if key not in t:
            continue
        value = t[key]
        if not isinstance(value, str) or not value.strip():
            found = f"{type_name(value)} `{value!r}`" if not isinstance(value, str) \
                else 'an empty string ""'
            ck.add(f"[rig.spin] {key}", f"expected the name of a CSV column of measured rig "
                   f'motion (e.g. `{key} = "table_angle"`), found {found}; the nominal motion '
                   "is given by `rate`, `nutation_angle` and `nutation_frequency`")
            ok = False
        out[key] = value
    for key in ("spin_up", "nutation_ramp", "nutation_start"):
        if key in t:
            out[key] = ck.number(t, "rig.spin", key, unit="s", nonnegative=True)
            ok = ok and out[key] is not None
    if "spin_angle" in t and "spin_rate" in t:
        ck.add("[rig.spin] spin_rate", "give the measured spin angle (`spin_angle`) or rate "
               "(`spin_rate`), not both")
        ok = False
    for column, schedule in (("spin_angle", "spin_up"), ("spin_rate", "spin_up"),
                             ("cone_angle", "nutation_ramp"), ("cone_angle", "nutation_start")):
        if column in t and schedule in t:
            ck.add(f"[rig.spin] {schedule}", f"a schedule for a motion the CSV column "
                   f"`{t[column]}` (`{column}`) already measures; remove one of them")
            ok = False
    if "nutation_start" in t and "nutation_ramp" not in t \
            or out.get("nutation_start") and out.get("nutation_ramp") == 0:
        ck.add("[rig.spin] nutation_start", "the coning can only start later with a ramp: give "
               "`nutation_ramp` > 0 s (a jump of the cone angle is not a rig motion)")
        ok = False
    return out, ok


def _read_rig(ck: Checker, doc: Mapping[str, Any], excitation: str | None,
              rig_kind: str | None = None) -> Rig | None:
    t = ck.table(doc, "rig", required=True)
    dry = grav = None
    if t is not None:
        dry = _dry_mass(ck, t, rig_kind)
        grav = ck.number(t, "rig", "gravity", unit="m/s^2", positive=True)
    present, crank = _read_crank(ck, doc, required=(excitation == "crank" and t is not None))
    spinning = rig_kind == "spinning"
    spin_present, spin = _read_spin(ck, doc, required=spinning and t is not None)
    if dry is _BAD or grav is None or (present and crank is None):
        return None
    if excitation == "crank" and crank is None:
        return None
    if spin_present and spin is None or (spinning and spin is None):
        return None
    return Rig(dry_mass=dry, gravity=grav, crank=crank, spin=spin if spinning else None)


_BAD = object()


def _dry_mass(ck: Checker, table: Mapping[str, Any], rig_kind: str | None) -> float | None | object:
    """``[rig] dry_mass``: a positive number (kg), or ``"estimate"`` / absent on the lateral
    rig (``None``: the container is not weighed, the fit estimates the rigid mass);
    :data:`_BAD` after a problem."""
    value = table.get("dry_mass", DRY_MASS_ESTIMATE)
    if value == DRY_MASS_ESTIMATE:
        if rig_kind == "spinning":
            ck.add("[rig] dry_mass", "the spinning rig needs the dry mass (a number in kg): its "
                   f"force_z and torques cannot tell it from the fixed liquid; found "
                   f"{'no key' if 'dry_mass' not in table else repr(value)}")
            return _BAD
        return None
    if isinstance(value, str):
        ck.add("[rig] dry_mass", f'expected a positive number in kg or "{DRY_MASS_ESTIMATE}" '
               f"(the container is not weighed), found the string {value!r}")
        return _BAD
    dry = ck.number(table, "rig", "dry_mass", unit="kg", positive=True)
    return _BAD if dry is None else dry


def _read_prediction(ck: Checker, doc: Mapping[str, Any]) -> tuple[bool, Prediction | None]:
    if "prediction" not in doc:
        return False, None
    t = ck.table(doc, "prediction", required=True)
    if t is None:
        return True, None
    pm = ck.number(t, "prediction", "pendulum_mass", unit="kg", positive=True)
    pl = ck.number(t, "prediction", "pendulum_length", unit="m", positive=True)
    fm = ck.number(t, "prediction", "fixed_mass", unit="kg", positive=True)
    zeta = ck.number(t, "prediction", "damping_ratio", unit="- (fraction of critical)",
                     nonnegative=True)
    if pm is None or pl is None or fm is None or zeta is None:
        return True, None
    return True, Prediction(pendulum_mass=pm, pendulum_length=pl, fixed_mass=fm,
                            damping_ratio=zeta)


def test_kind(doc: Mapping[str, Any]) -> tuple[str | None, str | None]:
    """``[test] excitation`` and ``rig`` when they are known values, else ``None``: what the
    other tables and the CSV are checked against even when ``[test]`` has problems."""
    t_table = doc.get("test")
    if not isinstance(t_table, Mapping):
        return None, None
    excitation = t_table.get("excitation")
    rig_kind = t_table.get("rig")
    return (excitation if excitation in KNOWN_EXCITATIONS else None,
            rig_kind if rig_kind in KNOWN_RIGS else None)


def read_tables(ck: Checker, doc: Mapping[str, Any]):
    """All tables of ``doc``: ``(test, tank, liquid, rig, prediction_present, prediction)``;
    a table with problems is ``None`` (the problems are in ``ck``)."""
    test = _read_test(ck, doc)
    excitation, rig_kind = test_kind(doc)
    tank = _read_tank(ck, doc)
    liquid = _read_liquid(ck, doc)
    rig = _read_rig(ck, doc, excitation, rig_kind)
    from .motion import read_motion  # six-axis records of a tank moved in 3-D

    motion_ok, motion, transducer = read_motion(ck, doc, rig_kind, excitation)
    if rig is not None and motion is not None:
        rig = replace(rig, motion=motion, transducer=transducer)
    rig = rig if motion_ok else None
    limits = _read_limits(ck, doc)
    if rig is not None and limits is not None:
        rig = replace(rig, limits=limits)
    pred_present, prediction = _read_prediction(ck, doc)
    return test, tank, liquid, rig, pred_present, prediction


def _read_limits(ck: Checker, doc: Mapping[str, Any]) -> "Limits | None":  # noqa: F821
    """The optional ``[rig.limits]`` table: every key present a positive number in its unit
    (:data:`~estimate.data.case.LIMIT_UNITS`); other keys are ignored like elsewhere."""
    from .case import LIMIT_UNITS, Limits

    rig = doc.get("rig")
    if not isinstance(rig, Mapping) or "limits" not in rig:
        return None
    t = ck.table(doc, "rig.limits", required=True)
    if t is None:
        return None
    values = {key: ck.number(t, "rig.limits", key, unit=unit, positive=True)
              for key, unit in LIMIT_UNITS.items() if key in t}
    if any(v is None for v in values.values()):
        return None
    return Limits(**values)
