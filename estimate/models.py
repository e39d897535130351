"""Analog models for test cases: the baseline, model specifications (``--model``) and the
rig values a case file fixes."""

from __future__ import annotations

from analogs import (DiaphragmSpring, FixedMass, HingeDamper, HingeSpring, LateralRig, Model,
                     Pendulum, QuadraticDamper)

from .case import Case

__all__ = ["BASELINE", "model_from_spec", "rig_values"]

#: The default model of ``slosh simulate`` and ``slosh fit``: fixed mass + first-mode
#: pendulum with hinge spring and linear hinge damper.
BASELINE = "fixed,p1"

_MODIFIERS = {
    "nospring": "pendulum without hinge spring",
    "quadratic": "adds a QuadraticDamper",
    "diaphragm": "adds a DiaphragmSpring",
}


def rig_for(case: Case) -> LateralRig:
    """The rig of ``case`` (lateral; measured or crank excitation)."""
    if case.test.rig != "lateral":
        raise ValueError(f"{case.path}: [test] rig = {case.test.rig!r} is not supported yet; "
                         "expected 'lateral'")
    return LateralRig(excitation=case.test.excitation)


def rig_values(case: Case) -> dict[str, float]:
    """Parameter values the case file fixes: dry mass, gravity and the crank geometry."""
    out = {"rig.dry_mass": case.rig.dry_mass, "rig.gravity": case.rig.gravity}
    if case.test.excitation == "crank" and case.crank is not None:
        out |= {"rig.crank_radius": case.crank.radius, "rig.rod_length": case.crank.rod_length,
                "rig.drive_frequency": case.crank.frequency}
    return out


def model_from_spec(spec: str, case: Case) -> Model:
    """Build a model from a comma-separated specification such as ``"fixed,p1,p2"``.

    Tokens: ``fixed`` (FixedMass); ``pN`` (Pendulum with HingeSpring and HingeDamper),
    optionally with modifiers after colons: ``pN:nospring`` (no hinge spring),
    ``pN:quadratic`` (adds a QuadraticDamper), ``pN:diaphragm`` (adds a DiaphragmSpring).
    """
    model: Model = Model((rig_for(case),))
    problems = []
    tokens = [tok.strip() for tok in spec.replace("+", ",").split(",") if tok.strip()]
    if not tokens:
        problems.append("empty model specification")
    for tok in tokens:
        name, *mods = tok.split(":")
        unknown = [m for m in mods if m not in _MODIFIERS]
        if unknown:
            problems.append(f"{tok!r}: unknown modifier {', '.join(map(repr, unknown))}; known: "
                            + ", ".join(f"{k} ({v})" for k, v in _MODIFIERS.items()))
            continue
        if name == "fixed":
            if mods:
                problems.append(f"{tok!r}: `fixed` takes no modifiers")
            model = model + FixedMass("fixed")
        elif name.startswith("p") and name[1:].isdigit():
            model = model + Pendulum(name) + HingeDamper(name)
            if "nospring" not in mods:
                model = model + HingeSpring(name)
            if "quadratic" in mods:
                model = model + QuadraticDamper(name)
            if "diaphragm" in mods:
                model = model + DiaphragmSpring(name)
        else:
            problems.append(f"{tok!r}: unknown component; expected `fixed` or `pN` (p1, p2, ...)")
    if problems:
        raise ValueError(f"--model {spec!r}: " + "; ".join(problems))
    return model.validate()
