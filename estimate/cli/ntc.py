"""`slosh ntc SPACECRAFT.toml`: nutation time constant of a spinning spacecraft, two ways.

Wire-up: ``estimate.cli`` calls :func:`add_parser` on its subparsers and dispatches to
:func:`run` (set as the ``func`` default).

File format (SI units; see ``examples/spacecraft.toml``)::

    [spacecraft]            # the bus: FreeSpacecraft parameters
    spin_rate = 5.0         # rad/s
    mass = 500.0            # kg
    inertia_x = 400.0       # kg m^2 (central, principal)
    inertia_y = 420.0
    inertia_z = 600.0
    translation = true      # optional (default true)

    [tank]                  # optional: tank origin relative to the bus centre of mass
    radius = 0.8            # m from the spin axis, along bus x
    height = 0.3            # m along the spin axis
    axis = "inward"         # "spin" (default) or "inward"

    [[analog]]              # one or more
    type = "spherical_pendulum"   # or "pendulum", "rotor", "fixed_mass"
    name = "p1"
    mass = 20.0
    length = 0.25
    hinge_height = 0.1
    damping = 2.0           # pendulums: hinge damping, N m s/rad (optional)
    stiffness = 0.0         # pendulums: hinge stiffness, N m/rad (optional)
    mount_radius = 0.8      # optional: place this analog off the tank origin (m, rad, m),
    mount_azimuth = 3.1416  #   in its own frame (`analogs.mounted.Mounted`), e.g. a second
    mount_height = 0.3      #   tank; mount_axis = "parallel" (default) or "inward"

    [ntc]                   # optional
    duration = 2000.0       # s
    initial_rate = 5e-4     # rad/s

``--fit FIT.json`` (a record of ``slosh fit``) gives the tank's analog instead of the file's
``[[analog]]`` tables (:func:`analog_tables`): the fit's fixed mass becomes a ``fixed_mass``
and each pendulum a ``spherical_pendulum`` (an axisymmetric tank sloshes alike in both
lateral axes) with the fitted mass, length, hinge damping and spring, at the tank origin of
``[tank]``; the heights and inertias a lateral record does not determine come from
``--set NAME=VALUE``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from analogs.errors import InputError

from ..outputs import Outputs, json_text
from ._cases import add_force, assignments

__all__ = ["add_parser", "analog_tables", "load_spacecraft", "run"]

_BUS_KEYS = ("spin_rate", "mass", "inertia_x", "inertia_y", "inertia_z")
_MOUNT_KEYS = {"mount_radius", "mount_azimuth", "mount_height", "mount_axis"}
_ANALOG_KEYS = {
    "rotor": {"name", "type", "axis", "inertia", "damping"},
    "pendulum": {"name", "type", "plane", "mass", "length", "hinge_height", "damping", "stiffness"},
    "spherical_pendulum": {"name", "type", "mass", "length", "hinge_height", "damping", "stiffness"},
    "fixed_mass": {"name", "type", "mass", "height", "inertia", "axial_inertia"},
}


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``ntc`` subcommand to an argparse subparsers object."""
    p = subparsers.add_parser(
        "ntc", help="nutation time constant of a spinning spacecraft with slosh analogs",
        description="Nutation time constant (NTC = 1/sigma, positive when the nutation grows) "
                    "from a nonlinear simulation (envelope fit) and from the eigenvalues of "
                    "the equations linearised about steady spin.")
    p.add_argument("spacecraft", help="spacecraft file (TOML): the bus, the tank's place and "
                   "the analogs; every key is described in examples/spacecraft.toml and in "
                   "`python3 -m pydoc estimate.cli.ntc`")
    p.add_argument("--fit", metavar="FIT.json",
                   help="the tank's analog from a fit record (`slosh fit --json`) instead of "
                        "the file's [[analog]] tables: fixed mass and pendulums (spherical, "
                        "as in an axisymmetric tank) with the fitted masses, lengths, damping "
                        "and springs, at the tank origin")
    p.add_argument("--set", metavar="NAME=VALUE", action="append", default=[],
                   help="with --fit: a value the fit does not give (p1.hinge_height, "
                        "fixed.height, fixed.inertia, fixed.axial_inertia: m, kg m^2) or one "
                        "to replace; repeatable")
    p.add_argument("--json", metavar="OUT.json", help="write both NTCs as JSON")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --json file")
    add_force(p)
    p.set_defaults(run=run)


#: Unit of every number of a spacecraft file (ranges: :data:`estimate.data.case.PHYSICAL_RANGES`).
_UNITS = {"spin_rate": "rad/s", "mass": "kg", "inertia_x": "kg m^2", "inertia_y": "kg m^2",
          "inertia_z": "kg m^2", "radius": "m", "height": "m", "length": "m",
          "hinge_height": "m", "damping": "N m s/rad", "stiffness": "N m/rad",
          "inertia": "kg m^2", "axial_inertia": "kg m^2", "mount_radius": "m",
          "mount_height": "m", "duration": "s", "initial_rate": "rad/s"}
_POSITIVE = {"mass", "inertia_x", "inertia_y", "inertia_z", "length", "inertia",
             "axial_inertia", "duration", "initial_rate"}


def _number(table: dict, key: str, where: str, problems: list[str], required: bool = True):
    from ..data._toml import range_problem

    if key not in table:
        if required:
            problems.append(f"{where}: missing `{key}`")
        return None
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != value:
        problems.append(f"{where}: `{key}` must be a number, got {value!r}")
        return None
    unit = _UNITS.get(key, "")
    why = range_problem(float(value), unit, positive=key in _POSITIVE)
    if why:
        problems.append(f"{where}: `{key}`: {why}, got {value!r}")
        return None
    return float(value)


def _triangle(values: dict[str, float], keys: tuple[str, str, str], where: str,
              problems: list[str]) -> None:
    """A rigid body's principal inertias obey the triangle inequality (each at most the sum
    of the other two: a mass distribution cannot give more)."""
    if all(k in values for k in keys):
        for k in keys:
            others = [values[o] for o in keys if o != k]
            if values[k] > sum(others) * (1 + 1e-12):
                problems.append(f"{where}: `{k}` = {values[k]:g} kg m^2 exceeds the sum of the "
                                f"other two principal inertias ({' + '.join(f'{o:g}' for o in others)}"
                                "): no rigid body has such inertias (triangle inequality)")
                return


def load_spacecraft(path: str | Path, *, analogs: list[dict] | None = None,
                    analogs_from: str | None = None):
    """Read a spacecraft file: returns ``(model, params, options)``.

    ``analogs`` replaces the file's ``[[analog]]`` tables (tables of the same keys, e.g.
    :func:`analog_tables` of a fit), named ``analogs_from`` in messages.

    Raises ``InputError`` listing every problem (file, table, key) at once.
    """
    from analogs import (
        FixedMass,
        HingeDamper,
        HingeSpring,
        Pendulum,
        Rotor,
        SphericalPendulum,
    )
    from analogs.mounted import Mounted
    from analogs.spacecraft import FreeSpacecraft

    from ..data.reader import MAX_CASE_FILE_BYTES
    from ..inputs import load_toml

    path = Path(path)
    doc = load_toml(path, "a spacecraft file (TOML)", limit=MAX_CASE_FILE_BYTES)
    problems: list[str] = []
    for key in sorted(set(doc) - {"spacecraft", "tank", "analog", "ntc"}):
        problems.append(f"{path}: unknown table `[{key}]`; expected [spacecraft], [tank], "
                        "[[analog]], [ntc]")
    bus = doc.get("spacecraft")
    if not isinstance(bus, dict):
        problems.append(f"{path}: missing table `[spacecraft]` with {', '.join(_BUS_KEYS)}")
        bus = {}
    where = f"{path} [spacecraft]"
    for key in sorted(set(bus) - set(_BUS_KEYS) - {"translation"}):
        problems.append(f"{where}: unknown key `{key}`")
    params = {f"bus.{k}": v for k in _BUS_KEYS
              if (v := _number(bus, k, where, problems)) is not None}
    _triangle({k: params[f"bus.{k}"] for k in _BUS_KEYS if f"bus.{k}" in params},
              ("inertia_x", "inertia_y", "inertia_z"), where, problems)
    translation = bus.get("translation", True)
    if not isinstance(translation, bool):
        problems.append(f"{where}: `translation` must be true or false, got {translation!r}")
        translation = True
    tank = doc.get("tank", {})
    where = f"{path} [tank]"
    for key in sorted(set(tank) - {"radius", "height", "axis"}):
        problems.append(f"{where}: unknown key `{key}`")
    for key in ("radius", "height"):
        if (v := _number(tank, key, where, problems, required=False)) is not None:
            params[f"bus.{key}"] = v
    axis = tank.get("axis", "spin")
    if axis not in ("spin", "inward"):
        problems.append(f"{where}: `axis` must be \"spin\" or \"inward\", got {axis!r}")
        axis = "spin"
    components = []
    given = analogs is not None
    analogs = analogs if given else doc.get("analog", [])
    if not isinstance(analogs, list) or not analogs:
        problems.append(f"{path}: no `[[analog]]` table; give at least one (rotor, pendulum, "
                        "spherical_pendulum, fixed_mass), or a fit with --fit")
        analogs = []
    for i, a in enumerate(analogs, 1):
        kind, name = a.get("type"), a.get("name", f"a{i}")
        where = f"{analogs_from} `{name}`" if given else f"{path} [[analog]] #{i}"
        if kind not in _ANALOG_KEYS:
            problems.append(f"{where}: `type` must be one of {', '.join(_ANALOG_KEYS)}, got {kind!r}")
            continue
        for key in sorted(set(a) - _ANALOG_KEYS[kind] - _MOUNT_KEYS):
            problems.append(f"{where}: unknown key `{key}` for a {kind}")
        if not isinstance(name, str) or not name.isidentifier():
            problems.append(f"{where}: `name` must be an identifier such as \"p1\", got {name!r}")
            continue
        bad_mount = [key for key in sorted(set(a) & _MOUNT_KEYS - {"mount_axis"})
                     if _number(a, key, where, problems, False) is None]
        if bad_mount:
            continue
        mount_axis = a.get("mount_axis", "parallel")
        if mount_axis not in ("parallel", "inward"):
            problems.append(f"{where}: `mount_axis` must be \"parallel\" or \"inward\", "
                            f"got {mount_axis!r}")
            continue
        mount = {k: float(a[k]) for k in _MOUNT_KEYS - {"mount_axis"} if k in a
                 and _number(a, k, where, [], False) is not None}
        wrap = (lambda c, axis=mount_axis, mount=mount: Mounted(c, axis=axis, **mount)) \
            if (mount or "mount_axis" in a) else (lambda c: c)
        values = {k: _number(a, k, where, problems, required=False)
                  for k in _ANALOG_KEYS[kind] - {"name", "type", "axis", "plane"} if k in a}
        if None in values.values():
            continue
        if kind == "fixed_mass" and "axial_inertia" in values:  # transverse inertia twice
            _triangle({"inertia_x": values.get("inertia", 0.0), "inertia_y":
                       values.get("inertia", 0.0), "inertia_z": values["axial_inertia"]},
                      ("inertia_x", "inertia_y", "inertia_z"), f"{where} (inertia, inertia, "
                      "axial_inertia)", problems)
        try:
            if kind == "rotor":
                components.append(wrap(Rotor(name, axis=a.get("axis", "z"), **values)))
            elif kind == "fixed_mass":
                components.append(wrap(FixedMass(name, **values)))
            else:
                hinge = {k: values.pop(k) for k in ("damping", "stiffness") if k in values}
                if kind == "pendulum":
                    components.append(wrap(Pendulum(name, plane=a.get("plane", "xz"), **values)))
                else:
                    components.append(wrap(SphericalPendulum(name, **values)))
                components.append(HingeDamper(name, damping=hinge.get("damping", 0.0)))
                if hinge.get("stiffness"):
                    components.append(HingeSpring(name, stiffness=hinge["stiffness"]))
        except (TypeError, ValueError) as err:
            problems.append(f"{where}: {err}")
    opts = doc.get("ntc", {})
    where = f"{path} [ntc]"
    for key in sorted(set(opts) - {"duration", "initial_rate"}):
        problems.append(f"{where}: unknown key `{key}`")
    options = {k: v for k in ("duration", "initial_rate")
               if (v := _number(opts, k, where, problems, required=False)) is not None}
    if problems:
        raise InputError(f"{len(problems)} problem{'s' if len(problems) > 1 else ''} in the "
                         "spacecraft file:\n  - " + "\n  - ".join(problems))
    model = FreeSpacecraft(translation=translation, tank_axis=axis)
    for c in components:
        model = model + c
    return model.validate(), params, options


#: The spacecraft file's keys of each analog a fit's component gives (``--set`` names are
#: dotted: ``p1.hinge_height``).
_FROM_FIT = {"fixed_mass": ("mass", "height", "inertia", "axial_inertia"),
             "spherical_pendulum": ("mass", "length", "hinge_height", "damping", "stiffness")}


def analog_tables(spec: str, values: dict[str, float], *, source: str = "the fit"
                  ) -> list[dict]:
    """The ``[[analog]]`` tables of the analog a fit describes: its model ``spec``
    (``"fixed,p1:nospring"``) with ``values`` by dotted name (the fit's, with ``--set``
    over them). The fixed mass becomes a ``fixed_mass``, each pendulum with its hinge
    damper and spring a ``spherical_pendulum`` (the lateral fit's planar pendulum swings
    alike along both lateral axes of an axisymmetric tank).

    Raises
    ------
    InputError
        Naming every value that is missing (the heights and inertias a lateral record does
        not determine) and every component with no spacecraft form.

    Examples
    --------
    >>> analog_tables("fixed,p1:nospring", {"fixed.mass": 1.5, "fixed.height": 0.1,
    ...     "fixed.inertia": 0.004, "fixed.axial_inertia": 0.006, "p1.mass": 1.3,
    ...     "p1.length": 0.055, "p1.hinge_height": 0.15, "p1.damping": 0.001})
    ...                                                  # doctest: +NORMALIZE_WHITESPACE
    [{'type': 'fixed_mass', 'name': 'fixed', 'mass': 1.5, 'height': 0.1, 'inertia': 0.004,
      'axial_inertia': 0.006},
     {'type': 'spherical_pendulum', 'name': 'p1', 'mass': 1.3, 'length': 0.055,
      'hinge_height': 0.15, 'damping': 0.001}]
    """
    from analogs import FixedMass, HingeDamper, HingeSpring, Pendulum
    from analogs.component import Attachment, Rig

    from .export import export_model

    model, _ = export_model(spec, values)
    tables: dict[str, dict] = {}
    problems, missing = [], []
    for c in model.components:
        if isinstance(c, Rig):
            continue
        if type(c) is FixedMass:
            tables[c.name] = {"type": "fixed_mass", "name": c.name}
        elif type(c) is Pendulum:
            tables[c.name] = {"type": "spherical_pendulum", "name": c.name}
        elif not isinstance(c, (HingeDamper, HingeSpring, Attachment)):
            problems.append(f"`{c.name}` ({type(c).__name__}) has no form in a spacecraft file")
    for c in model.components:
        if isinstance(c, Attachment) and not isinstance(c, (HingeDamper, HingeSpring)):
            problems.append(f"`{c.name}` carries a {type(c).__name__}, which the spacecraft's "
                            "analogs do not have (fit with a linear hinge damper)")
    for name, table in tables.items():
        keys = list(_FROM_FIT[table["type"]])
        springs = any(isinstance(c, HingeSpring) and c.name == name for c in model.components)
        for key in keys:
            dotted = f"{name}.{key}"
            if key == "stiffness" and not springs:
                continue
            if dotted in values:
                table[key] = float(values[dotted])
            elif key not in ("damping",):
                missing.append(f"`{dotted}`")
    if missing:
        problems.append(f"{source} does not give {', '.join(missing)} (a lateral record does "
                        "not determine them): give each with --set NAME=VALUE (heights in m "
                        "above the tank origin, inertias in kg m^2)")
    if problems:
        raise InputError(f"--fit: {'; '.join(problems)}")
    return list(tables.values())


def run(args: argparse.Namespace) -> int:
    """Run ``slosh ntc``; returns the exit status."""
    from ..analysis.ntc import nutation_time_constant

    if args.set and not args.fit:
        raise InputError("`--set` gives values of a fit's analog: use it with `--fit FIT.json`")
    outputs = Outputs(overwrite=args.overwrite,
                      inputs=[args.spacecraft] + ([args.fit] if args.fit else []))
    outputs.file("--json", args.json).check()
    analogs = None
    if args.fit:
        from ..fitting.record import fit_notes, read_fit

        for note in fit_notes(args.fit, force=args.force):
            print(f"warning: {note}", file=sys.stderr)
        fit = read_fit(args.fit)
        given = assignments(args.set)
        analogs = analog_tables(fit.model_spec, {**fit.values, **given}, source=str(args.fit))
        known = {f"{t['name']}.{k}" for t in analogs for k in _FROM_FIT[t["type"]]}
        unknown = [n for n in given if n not in known]
        if unknown:
            raise InputError(f"--set {', '.join(unknown)}: not a value of the analog of "
                             f"{args.fit} ({fit.model_spec}); it has {', '.join(sorted(known))}")
        replaced = _analog_count(args.spacecraft)
        if replaced:
            print(f"note: {args.spacecraft}: its {replaced} [[analog]] table(s) are replaced by "
                  f"the analog of {args.fit} ({fit.model_spec})", file=sys.stderr)
    model, params, options = load_spacecraft(args.spacecraft, analogs=analogs,
                                             analogs_from=args.fit)
    ntc = nutation_time_constant(model, params, **options)
    print(f"{args.spacecraft}: {model!r}")
    print(ntc.report())
    out = {"ntc_simulated_s": ntc.simulated, "ntc_linearized_s": ntc.linearized,
           "growth_rate_simulated_per_s": ntc.growth_rate_simulated,
           "growth_rate_linearized_per_s": ntc.growth_rate_linearized,
           "nutation_frequency_rad_s": ntc.nutation_frequency,
           "relative_difference": ntc.relative_difference, "grows": ntc.grows}
    if analogs is not None:
        out["analog_from_fit"] = {"fit": str(args.fit), "analogs": analogs}
    with outputs.writing() as paths:
        if args.json:
            paths["--json"].write_text(json_text(out))
    if ntc.relative_difference > 0.02:
        print("warning: the two methods differ by more than 2 %; simulate longer "
              "([ntc] duration) or with a smaller initial_rate", file=sys.stderr)
    return 0


def _analog_count(path: str | Path) -> int:
    """How many ``[[analog]]`` tables the spacecraft file has (0 when unreadable: the loader
    says why)."""
    from ..data.reader import MAX_CASE_FILE_BYTES
    from ..inputs import load_toml

    try:
        doc = load_toml(Path(path), "a spacecraft file (TOML)", limit=MAX_CASE_FILE_BYTES)
    except (OSError, InputError):
        return 0
    analogs = doc.get("analog")
    return len(analogs) if isinstance(analogs, list) else 0
