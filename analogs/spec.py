"""The model specification grammar (``"fixed,p1:nospring,r1"``, ``slosh fit --model``): a
model built from a specification on a rig (:func:`model_from_spec`) and the specification of
a model (:func:`spec_of`, :meth:`analogs.Model.spec`).

Tokens, comma-separated (``+`` works as a comma): ``fixed`` (:class:`FixedMass`); ``pN``
with N from 1 to :data:`analogs.tank.prediction.MAX_MODES` (the modes the tank prediction
gives initial values for): a :class:`Pendulum` (a :class:`SphericalPendulum` on the
spinning rig, with the ``spherical`` modifier, or where the caller asks for one: a six-axis
record that moves the tank out of the x-z plane) with :class:`HingeSpring` and
:class:`HingeDamper`, optionally with modifiers after colons (:data:`MODIFIERS`); on a rig
that rotates, ``rotor`` or ``rN``: a :class:`Rotor` about the tangential tank axis
:data:`ROTOR_AXIS`.
"""

from __future__ import annotations

from .component import Attachment, Rig
from .errors import InputError
from .fixed_mass import FixedMass
from .hinge import DiaphragmSpring, HingeDamper, HingeSpring, QuadraticDamper
from .model import Model
from .pendulum import Pendulum, SphericalPendulum
from .rotor import Rotor
from .spinning import SpinningRig

__all__ = ["MODIFIERS", "ROTOR_AXIS", "model_from_spec", "spec_of", "spec_problems"]

#: Tank axis of rotor analogs on the spinning rig: ``T.y``, the tangential direction (the
#: way the tank origin moves), about which the nutation drives a rotor (the spin-axis
#: component of the tank's angular acceleration is zero, see :class:`analogs.SpinningRig`).
ROTOR_AXIS = "y"

#: The modifiers of a ``pN`` token, with what each does.
MODIFIERS = {
    "nospring": "pendulum without hinge spring",
    "quadratic": "adds a QuadraticDamper",
    "diaphragm": "adds a DiaphragmSpring",
    "spherical": "a SphericalPendulum: slosh along both tank axes (swirl)",
}

#: Attachments a ``pN`` token may carry, by modifier (None: always there).
_ATTACHMENTS = {HingeDamper: None, HingeSpring: "spring", QuadraticDamper: "quadratic",
                DiaphragmSpring: "diaphragm"}


def _max_modes() -> int:
    from .tank.prediction import MAX_MODES  # the tank package only when a spec is read

    return MAX_MODES


def _tokens_text(spinning: bool) -> str:
    rotor = "; `rotor` or `rN` (rotor, spinning rig)" if spinning else ""
    return (f"valid tokens: `fixed`; `p1` to `p{_max_modes()}` (pendulum of slosh mode N, the "
            "modes the tank prediction gives), optionally with modifiers "
            + ", ".join(f"`:{m}`" for m in MODIFIERS) + f"{rotor}; e.g. `fixed,p1,p2:quadratic`")


def _number_of(name: str, letter: str) -> int | None:
    """N of ``pN``/``rN`` written without leading zeros, else None."""
    digits = name[1:]
    if name[:1] != letter or not digits.isascii() or not digits.isdigit():
        return None
    return int(digits) if digits == str(int(digits)) else None


def _tokens(spec: str) -> list[str]:
    return [tok.strip() for tok in spec.replace("+", ",").split(",") if tok.strip()]


def _build(spec: str, rig: Rig, spherical: bool = False) -> tuple[Model, list[str]]:
    """The model of ``spec`` on ``rig`` and every problem of the specification; every
    pendulum a :class:`SphericalPendulum` when ``spherical`` (or on the spinning rig)."""
    model: Model = Model((rig,))
    spinning = isinstance(rig, SpinningRig)
    max_modes = _max_modes()
    problems = []
    tokens = _tokens(spec)
    if not tokens:
        problems.append("empty model specification")
    names = [tok.split(":")[0] for tok in tokens]
    for name in sorted({n for n in names if names.count(n) > 1}):
        problems.append(f"`{name}` is given {names.count(name)} times; give each component once")
    for tok in tokens:
        name, *mods = tok.split(":")
        unknown = [m for m in mods if m not in MODIFIERS]
        if unknown:
            problems.append(f"`{tok}`: unknown modifier {', '.join(map(repr, unknown))}; known: "
                            + ", ".join(f"{k} ({v})" for k, v in MODIFIERS.items()))
            continue
        pendulum, rotor = _number_of(name, "p"), _number_of(name, "r")
        if name == "fixed":
            if mods:
                problems.append(f"`{tok}`: `fixed` takes no modifiers")
            model = model + FixedMass("fixed")
        elif name == "rotor" or rotor is not None:
            if not spinning:
                problems.append(f"`{tok}`: a rotor needs a rig that rotates (`rig = \"spinning\"`)")
            elif mods:
                problems.append(f"`{tok}`: a rotor takes no modifiers")
            elif rotor == 0:
                problems.append(f"`{tok}`: rotors are numbered from r1")
            else:
                model = model + Rotor(name, axis=ROTOR_AXIS)
        elif pendulum is not None and 1 <= pendulum <= max_modes:
            swirls = spinning or spherical or "spherical" in mods
            pend = SphericalPendulum(name) if swirls else Pendulum(name)
            model = model + pend + HingeDamper(name)
            if "nospring" not in mods:
                model = model + HingeSpring(name)
            if "quadratic" in mods:
                model = model + QuadraticDamper(name)
            if "diaphragm" in mods:
                model = model + DiaphragmSpring(name)
        elif pendulum is not None:
            problems.append(f"`{tok}`: pendulums are numbered by slosh mode, from p1 to "
                            f"p{max_modes}")
        else:
            problems.append(f"`{tok}`: unknown component")
    return model, problems


def spec_problems(spec: str, rig: Rig, *, option: str = "--model") -> list[str]:
    """Why ``spec`` cannot be built on ``rig``: one message naming ``option`` and listing
    every problem, or none.

    Parameters
    ----------
    spec : str
        A model specification (``"fixed,p1"``).
    rig : Rig
        The rig it is for (a rotor needs a :class:`SpinningRig`).
    option : str, default "--model"
        Where the specification came from (an option, or a file and key), for the message.
    """
    _, problems = _build(spec, rig)
    return [_message(spec, rig, option, problems)] if problems else []


def _message(spec: str, rig: Rig, option: str, problems: list[str]) -> str:
    return (f"{option} {spec!r}: " + "; ".join(problems) + "; "
            + _tokens_text(isinstance(rig, SpinningRig)))


def model_from_spec(spec: str, rig: Rig, *, option: str = "--model",
                    spherical: bool = False) -> Model:
    """The model of the specification ``spec`` (module docstring) on ``rig``, validated;
    it knows its specification (:meth:`Model.spec` gives ``spec`` back, its tokens as
    given).

    Parameters
    ----------
    spec : str
        Comma-separated tokens, e.g. ``"fixed,p1:nospring"``.
    rig : Rig
        The rig the components ride on.
    option : str, default "--model"
        Where the specification came from (an option, or a file and key): errors name it.
    spherical : bool, default False
        Every pendulum a :class:`SphericalPendulum`, as ``pN:spherical`` makes one: for a rig
        whose record sees slosh out of the x-z plane (a six-axis record that moves the tank
        along y, in roll or in yaw, or measures ``force_y``, ``torque_x`` or ``torque_z``;
        :func:`estimate.data.models.sees_transverse`). The spinning rig's pendulums are
        spherical anyway.

    Raises
    ------
    InputError
        Naming ``option``, listing every problem and the valid tokens.

    Examples
    --------
    >>> from analogs import LateralRig
    >>> model_from_spec("fixed,p1:quadratic", LateralRig()).spec()
    'fixed,p1:quadratic'
    """
    model, problems = _build(spec, rig, spherical)
    if problems:
        raise InputError(_message(spec, rig, option, problems))
    return Model(model.components, spec=",".join(_tokens(spec))).validate()


def spec_of(model: Model) -> str | None:
    """The specification :func:`model_from_spec` builds ``model`` from, read from its
    components (``"fixed,p1:nospring"``), or None when the model holds a component the
    grammar has no token for (a diagnosis's library term, a rig friction, a pendulum under
    another name). A :class:`SphericalPendulum` off the spinning rig reads ``pN:spherical``.

    Parameters
    ----------
    model : Model
        Any model.

    Examples
    --------
    >>> from analogs import LateralRig, FixedMass, Pendulum, HingeDamper, QuadraticDamper
    >>> spec_of(LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeDamper("p1")
    ...         + QuadraticDamper("p1"))
    'fixed,p1:nospring:quadratic'
    """
    attached: dict[str, set[str | None]] = {}
    tokens: list[str] = []
    swirling: dict[str, bool] = {}
    spinning = any(isinstance(c, SpinningRig) for c in model.components)
    for c in model.components:
        if isinstance(c, Rig):
            continue
        if isinstance(c, Attachment):
            kind = _ATTACHMENTS.get(type(c), "?")
            if kind == "?":
                return None
            attached.setdefault(c.name, set()).add(kind)
        elif type(c) is FixedMass and c.name == "fixed":
            tokens.append("fixed")
        elif type(c) in (Pendulum, SphericalPendulum) and _number_of(c.name, "p"):
            tokens.append(c.name)
            swirling[c.name] = type(c) is SphericalPendulum
        elif type(c) is Rotor and (c.name == "rotor" or _number_of(c.name, "r")):
            tokens.append(c.name)
        else:
            return None
    out = []
    for tok in tokens:
        kinds = attached.pop(tok, set())
        if not tok.startswith("p"):
            if kinds:
                return None
            out.append(tok)
            continue
        if None not in kinds:  # every pendulum of the grammar has its hinge damper
            return None
        mods = [] if "spring" in kinds else ["nospring"]
        mods += [m for m in ("quadratic", "diaphragm") if m in kinds]
        if swirling.get(tok) and not spinning:  # the spinning rig's pendulums swirl anyway
            mods.append("spherical")
        out.append(":".join([tok, *mods]))
    return ",".join(out) if out and not attached else None
