"""``derive(model)``: symbolic derivation once, then cached CasADi functions."""

from __future__ import annotations

import contextlib
import threading
import warnings

from analogs.component import SourceUnavailable
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
        Read and write the on-disk cache (see :mod:`derive.cache`). A model whose component
        source cannot be read (a class made with ``exec``) is always derived anew, with a
        warning once per class.

    Examples
    --------
    >>> from analogs import LateralRig, FixedMass, Pendulum, HingeDamper
    >>> from derive import derive
    >>> dm = derive(LateralRig() + FixedMass("fixed") + Pendulum("p1") + HingeDamper("p1"))
    >>> dm.coordinates
    ('p1.theta',)
    """
    model.validate()
    key = None
    if use_cache:
        try:
            key = cache.cache_key(model.structure_key())
        except SourceUnavailable as err:
            _warn_uncached(err)
    live = _live_entry(key) if key is not None else None
    if live is not None:
        fns, meta, memo = live
        return _derived_model(model, fns, meta, memo, from_cache=True)
    lock = (cache.building(cache.cache_dir() / key) if key is not None
            else contextlib.nullcontext())
    with lock:  # another process deriving the same model: wait for its entry
        hit = cache.load(key) if key is not None else None
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
            if key is not None:
                cache.store(key, fns, meta)
            from_cache = False
    memo: dict = {}
    if key is not None:
        _keep_live(key, fns, meta, memo)
    return _derived_model(model, fns, meta, memo, from_cache=from_cache)


def _derived_model(model: Model, fns: dict, meta: dict, memo: dict, *,
                   from_cache: bool) -> DerivedModel:
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
        _memo=memo,
    )


#: Derived structures kept in memory, per thread (CasADi's symbolic objects are not shared
#: between threads): a process that fits many records or models (a diagnosis, a campaign)
#: loads each structure once and keeps the functions built from it (maps, compiled RK4
#: steps, simulators) in the shared ``_memo``. An entry is used only while the cache file
#: it came from is unchanged (same size and modification time), so a rewritten, damaged or
#: removed entry is read again.
_LIVE = threading.local()
_LIVE_SIZE = 8


def _stamp(key: str) -> tuple | None:
    path = cache.cache_dir() / f"{key}.json"
    try:
        st = path.stat()
    except OSError:
        return None
    return (str(path.resolve()), st.st_ino, st.st_size, st.st_mtime_ns)


def _live_entry(key: str):
    entries = getattr(_LIVE, "entries", None)
    if not entries or key not in entries:
        return None
    stamp, value = entries[key]
    if stamp is None or stamp != _stamp(key):
        del entries[key]
        return None
    return value


def _keep_live(key: str, fns: dict, meta: dict, memo: dict) -> None:
    entries = getattr(_LIVE, "entries", None)
    if entries is None:
        entries = _LIVE.entries = {}
    entries.pop(key, None)
    entries[key] = (_stamp(key), (fns, meta, memo))
    while len(entries) > _LIVE_SIZE:
        entries.pop(next(iter(entries)))


_WARNED: set[tuple[str, int]] = set()


def _warn_uncached(err: SourceUnavailable) -> None:
    tag = (err.cls.__qualname__, id(err.cls))
    if tag not in _WARNED:
        _WARNED.add(tag)
        warnings.warn(f"{err}; its equations are derived without the on-disk cache",
                      RuntimeWarning, stacklevel=3)
