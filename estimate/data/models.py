"""Analog models for test cases: the baseline, model specifications (``--model``) and the
rig values a case file fixes."""

from __future__ import annotations

from analogs import LateralRig, Model, MotionRig, SpinningRig
from analogs.component import Rig
from analogs.errors import InputError
from analogs.spec import ROTOR_AXIS, spec_of
from analogs.spec import model_from_spec as spec_model

from .case import Case, Transducer

__all__ = ["BASELINE", "ROTOR_AXIS", "model_for_case", "model_from_spec", "model_spec", "rig_for",
           "rig_values", "sees_transverse"]

#: The default model of ``slosh simulate`` and ``slosh fit``: fixed mass + first-mode
#: pendulum with hinge spring and linear hinge damper.
BASELINE = "fixed,p1"


def rig_for(case: Case) -> Rig:
    """The rig of ``case``: :class:`analogs.LateralRig` (measured or crank excitation) or
    :class:`analogs.SpinningRig` (``[rig.spin]`` gives its tank axis and whether gravity
    acts)."""
    if case.test.rig == "spinning":
        spin = case.rig.spin
        if spin is None:
            raise InputError(f"{case.path}: `rig = \"spinning\"` needs a `[rig.spin]` table")
        return SpinningRig(gravity=spin.gravity_on, tank_axis=spin.tank_axis, motion=spin.motion)
    if case.test.rig != "lateral":
        raise InputError(f"{case.path}: [test] rig = {case.test.rig!r} is not supported; "
                         "expected 'lateral' or 'spinning'")
    motion = _motion_of(case)
    if motion is not None:  # a six-axis record of a tank moved in 3-D
        return MotionRig(axes=motion.axes)
    return LateralRig(excitation=case.test.excitation)


def _motion_of(case) -> object | None:
    """The case's ``[rig.motion]`` (``None`` also for the stand-in cases that commands build
    to name a rig: they carry no six-axis motion)."""
    return getattr(getattr(case, "rig", None), "motion", None)


#: A six-axis record's signs of motion out of the x-z plane: a pendulum on its rig is then
#: spherical (it can swirl), else planar in x-z.
_TRANSVERSE_AXES = ("y", "roll", "yaw")
_TRANSVERSE_CHANNELS = ("force_y", "torque_x", "torque_z")


def sees_transverse(case: Case) -> bool:
    """Whether a six-axis record (``[rig.motion]``) moves the tank out of the x-z plane or
    measures a channel that only motion out of it drives (``force_y``, ``torque_x``,
    ``torque_z``): its pendulums are then :class:`~analogs.SphericalPendulum` (slosh along
    both tank axes, swirl), else planar."""
    motion = _motion_of(case)
    if motion is None:
        return False
    return bool(set(motion.axes) & set(_TRANSVERSE_AXES)
                or set(case.channels) & set(_TRANSVERSE_CHANNELS))


def model_for_case(model: Model, case: Case) -> Model:
    """``model`` on the rig ``case`` needs: a lateral model built for a measured case drives
    a crank case through its crank (and the other way round); a spinning-rig model takes
    the rig motion the case gives (constant rates or input signals); other rigs are kept."""
    rig = model.rig
    spin = case.rig.spin
    if isinstance(rig, SpinningRig) and spin is not None and rig.motion != spin.motion:
        keep = {k: v for k, v in rig.given_values.items() if k in ("dry_mass", "radius", "height",
                                                                "gravity")}
        return model.replace(SpinningRig(gravity=rig.with_gravity, tank_axis=rig.tank_axis,
                                         motion=spin.motion, name=rig.name,
                                         bounds={k: v for k, v in rig.given_bounds.items() if k in keep},
                                         **keep))
    motion = _motion_of(case)
    if isinstance(rig, (LateralRig, MotionRig)) and motion is not None \
            and getattr(rig, "axes", None) != motion.axes:
        shared = {"dry_mass", "gravity"}  # a lateral model on a six-axis record's rig
        if isinstance(rig, MotionRig):
            shared |= {k for k in rig.parameters if k.startswith("transducer_")}
        moved = MotionRig(axes=motion.axes, name=rig.name,
                          bounds={k: v for k, v in rig.given_bounds.items() if k in shared},
                          **{k: v for k, v in rig.given_values.items() if k in shared})
        return Model(moved if c is rig else c for c in model.components)
    if isinstance(rig, LateralRig) and case.test.rig == "lateral" \
            and rig.excitation != case.test.excitation:
        shared = {"dry_mass", "gravity"}  # what both excitations of the rig have
        swapped = LateralRig(excitation=case.test.excitation, name=rig.name,
                             bounds={k: v for k, v in rig.given_bounds.items() if k in shared},
                             **{k: v for k, v in rig.given_values.items() if k in shared})
        return model.replace(swapped)
    return model


def rig_values(case: Case) -> dict[str, float]:
    """Parameter values the case file fixes: dry mass (when weighed), gravity and the crank
    geometry (a six-axis record: the transducer's point and turn, ``[rig.transducer]``), or
    the spinning rig's geometry and constant motion (``[rig.spin]`` -> ``rig.radius``,
    ``rig.height`` and, without measured motion or schedules, ``rig.spin_rate``,
    ``rig.nutation_angle``, ``rig.nutation_frequency``)."""
    spin = case.rig.spin
    if case.test.rig == "spinning" and spin is not None:
        out = {"rig.dry_mass": case.rig.dry_mass, "rig.radius": spin.radius,
               "rig.height": spin.height}
        if spin.motion == "constant":  # else the rig motion is the rig's input signals
            out |= {"rig.spin_rate": spin.rate, "rig.nutation_angle": spin.nutation_angle,
                    "rig.nutation_frequency": spin.nutation_frequency}
        if spin.gravity_on:
            out["rig.gravity"] = case.rig.gravity
        return out
    out = {"rig.gravity": case.rig.gravity}
    if case.rig.dry_mass is not None:  # else the container is not weighed: estimated
        out["rig.dry_mass"] = case.rig.dry_mass
    if _motion_of(case) is not None:  # where the six-axis transducer measures
        tr = case.rig.transducer or Transducer()
        out |= {f"rig.transducer_{k}": getattr(tr, k)
                for k in ("x", "y", "z", "roll", "pitch", "yaw")}
    if case.test.excitation == "crank" and case.crank is not None:
        out |= {"rig.crank_radius": case.crank.radius, "rig.rod_length": case.crank.rod_length,
                "rig.drive_frequency": case.crank.frequency}
    return out


def model_from_spec(spec: str, case: Case, *, option: str = "--model") -> Model:
    """Build a model from a comma-separated specification ``spec`` such as
    ``"fixed,p1,p2"``, on the rig of ``case`` (:func:`rig_for`); the grammar is
    :mod:`analogs.spec`'s (:func:`analogs.spec.model_from_spec`).

    Tokens: ``fixed`` (FixedMass); ``pN`` with N from 1 to ``MAX_MODES`` (6: the modes the
    tank prediction gives initial values for) (Pendulum with HingeSpring and HingeDamper;
    a SphericalPendulum on the spinning rig and on a six-axis record that sees motion out of
    the x-z plane, :func:`sees_transverse`), optionally with modifiers after colons:
    ``pN:nospring`` (no hinge spring), ``pN:quadratic`` (adds a QuadraticDamper),
    ``pN:diaphragm`` (adds a DiaphragmSpring), ``pN:spherical`` (a SphericalPendulum: the
    liquid may swirl); spinning rig only: ``rotor`` or ``rN``
    (a Rotor about the tangential tank axis :data:`ROTOR_AXIS`, coupled by a viscous damper).
    Errors name the option (``option``: ``--model``, or the file and key the specification
    came from) and list the valid tokens.

    Examples
    --------
    >>> model = model_from_spec("fixed,p1:nospring,r1", spinning_case)   # doctest: +SKIP
    """
    return spec_model(spec, rig_for(case), option=option, spherical=sees_transverse(case))


def model_spec(model: Model) -> str | None:
    """The specification :func:`model_from_spec` builds ``model`` from (``"fixed,p1:nospring"``),
    or None when the model holds a component the grammar has no token for
    (:func:`analogs.spec.spec_of`; :meth:`analogs.Model.spec` gives a specification as given).

    Examples
    --------
    >>> from analogs import LateralRig, FixedMass, Pendulum, HingeDamper, QuadraticDamper
    >>> model_spec(LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeDamper("p1")
    ...            + QuadraticDamper("p1"))
    'fixed,p1:nospring:quadratic'
    """
    return spec_of(model)
