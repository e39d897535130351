"""``derive(model)``: symbolic derivation once, then cached CasADi functions."""

from __future__ import annotations

from analogs.model import Model

from . import cache
from .derived import DerivedModel

__all__ = ["derive"]


def derive(model: Model, *, use_cache: bool = True) -> DerivedModel:
    """Derive the equations of motion and rig outputs of ``model``.

    The first call for a model structure runs SymPy (``sympy.physics.mechanics``,
    Lagrange's method with Rayleigh dissipation) and stores CasADi functions on disk;
    later calls, also in new processes, load them without importing SymPy.

    Parameters
    ----------
    model : analogs.Model
        A validated model (one rig plus components).
    use_cache : bool, default True
        Read and write the on-disk cache (see :mod:`derive.cache`).

    Examples
    --------
    >>> from analogs import LateralRig, FixedMass, Pendulum, HingeDamper
    >>> from derive import derive
    >>> dm = derive(LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeDamper("p1"))
    >>> dm.coordinates
    ('p1.theta',)
    """
    model.validate()
    key = cache.cache_key(model.structure_key())
    hit = cache.load(key) if use_cache else None
    if hit is not None:
        fns, meta = hit
        from_cache = True
    else:
        from ._lagrange import assemble
        from ._to_casadi import dependencies, to_casadi

        sym = assemble(model)
        fns = to_casadi(sym)
        meta = {
            "coordinates": list(sym.coordinates),
            "inputs": list(sym.inputs),
            "input_units": list(sym.input_units),
            "parameters": list(sym.parameters),
            "measured": list(sym.measured),
            "dependencies": dependencies(fns, sym.parameters),
        }
        if use_cache:
            cache.store(key, fns, meta)
        from_cache = False
    return DerivedModel(
        model=model,
        coordinates=tuple(meta["coordinates"]),
        inputs=tuple(meta["inputs"]),
        input_units=tuple(meta["input_units"]),
        parameter_names=tuple(meta["parameters"]),
        measured=tuple(meta["measured"]),
        rhs=fns["rhs"],
        outputs=fns["outputs"],
        mass_matrix=fns["mass_matrix"],
        forcing=fns["forcing"],
        dependencies={k: tuple(v) for k, v in meta["dependencies"].items()},
        from_cache=from_cache,
    )
