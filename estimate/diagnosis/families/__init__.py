"""The diagnosis families: one module each, one :class:`~.base.Family` object each (its
cause, what it adds, how it is screened or scanned, its start from the evidence, its
plausibility rule and description). The registry is every family defined in this
package's modules: adding a family is adding a module (and its test); the cause list, the
screening and the proposals are derived from :data:`FAMILIES`.

Hinge nonlinearities (:mod:`.hinge`) and the hinge-torque library (:mod:`.library`),
measurement models (:mod:`.measurement`: offset and drift, rig friction), extra slosh
modes (:mod:`.slosh_mode`), a diaphragm's stiffness (:mod:`.diaphragm`), a sensor delay
(:mod:`.delay`) and the rotating-tank families (:mod:`.rotor`, :mod:`.rotary`).
"""

from __future__ import annotations

import importlib
import pkgutil

from .base import Context, Family, Proposal, Score, Term

__all__ = ["FAMILIES", "CAUSES", "Family", "Context", "Proposal", "Score", "Term", "family"]


def _discover() -> tuple[Family, ...]:
    """One instance of every concrete family class in this package's modules, in module
    name order (a family with an empty ``cause`` is a base class)."""
    found: dict[str, Family] = {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name == "base":
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        for obj in vars(module).values():
            if isinstance(obj, type) and issubclass(obj, Family) and obj.cause \
                    and obj.__module__ == module.__name__:
                if obj.cause in found:
                    raise RuntimeError(f"two diagnosis families name the cause {obj.cause!r}: "
                                       f"{type(found[obj.cause]).__name__} and {obj.__name__}")
                found[obj.cause] = obj()
    return tuple(found.values())


#: Every diagnosis family.
FAMILIES: tuple[Family, ...] = _discover()
#: The causes a diagnosis can name.
CAUSES: tuple[str, ...] = tuple(f.cause for f in FAMILIES)


def family(cause: str) -> Family:
    """The family that names ``cause``."""
    for f in FAMILIES:
        if f.cause == cause:
            return f
    raise KeyError(f"no diagnosis family names the cause {cause!r} (known: {', '.join(CAUSES)})")
