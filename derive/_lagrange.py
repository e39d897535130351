"""Symbolic assembly: declared components -> Lagrangian -> M(q, p) qdd = f(q, qd, u, p, t).

Only this module (and :mod:`analogs.declaration`) imports SymPy. The mass matrix is never
inverted symbolically; outputs keep ``qdd`` as symbols, solved numerically in CasADi.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.physics import mechanics as me

from analogs.component import Attachment, Rig
from analogs.declaration import TIME, Collected, Declaration, FrameDeclaration, Frames, Namespace
from analogs.errors import InputError
from analogs.model import Model

from .derived import OUTPUT_NAMES

__all__ = ["SymbolicModel", "assemble", "OUTPUT_NAMES"]


@dataclass(frozen=True)
class SymbolicModel:
    """Equations of a model with plain symbols in place of functions of time.

    ``mass_matrix * qdd = forcing``; ``outputs`` may contain ``qdd``.
    """

    coordinates: tuple[str, ...]
    q: tuple[sp.Symbol, ...]
    qd: tuple[sp.Symbol, ...]
    qdd: tuple[sp.Symbol, ...]
    inputs: tuple[str, ...]
    input_units: tuple[str, ...]
    u: tuple[sp.Symbol, ...]
    parameters: tuple[str, ...]
    p: tuple[sp.Symbol, ...]
    t: sp.Symbol
    mass_matrix: sp.Matrix
    forcing: sp.Matrix
    outputs: tuple[sp.Expr, ...]
    measured: tuple[str, ...]


def assemble(model: Model) -> SymbolicModel:
    """Derive the equations of motion and the rig outputs of ``model`` with SymPy."""
    model.validate()
    t = TIME
    N, T = me.ReferenceFrame("N"), me.ReferenceFrame("T")
    shared = Frames(N, T, me.Vector(0), me.Vector(0))
    collected = Collected()
    psym = {p.name: sp.Symbol(p.name, real=True) for p in model.parameters}

    def local_params(c):
        return {p.local_name: psym[p.name] for p in c.bound_parameters()}

    rig = model.rig
    frame_decl = FrameDeclaration(rig.name, local_params(rig), shared, collected)
    if rig.coordinates:
        # A rig that owns generalized coordinates (a free body such as a spacecraft bus)
        # sees them in declare_frame as `f.q`/`f.qd`, and declares bodies and energies in
        # declare(k) like a component; the symbols are the same (same names).
        rig_q = {name: me.dynamicsymbols(f"{rig.prefix}.{name}") for name in rig.coordinates}
        frame_decl.q = Namespace(rig_q, f"rig {rig.name!r}")
        frame_decl.qd = Namespace({k: v.diff(t) for k, v in rig_q.items()}, f"rig {rig.name!r}")
    rig.declare_frame(frame_decl)

    coords: list[tuple[str, sp.Function]] = []
    hosts: dict[str, Declaration] = {}
    for c in model.components:
        if isinstance(c, Attachment) or (isinstance(c, Rig) and not c.coordinates):
            continue
        qs = {name: me.dynamicsymbols(f"{c.prefix}.{name}") for name in c.coordinates}
        coords += [(f"{c.prefix}.{name}", s) for name, s in qs.items()]
        k = Declaration(c.name, qs, local_params(c), shared, collected)
        c.declare(k)
        hosts[c.name] = k
    host_components = {c.name: c for c in model.components if not isinstance(c, (Rig, Attachment))}
    for c in model.components:
        if isinstance(c, Attachment):
            hk = hosts[c.host]
            k = Declaration(c.host, {}, local_params(c), shared, collected,
                            host=hk, hinge=host_components[c.host].hinge_angles)
            c.declare(k)

    g = shared.gravity
    r_O = shared.origin_position
    kinetic = sp.S.Zero
    potential = sp.Add(*collected.potential)
    force = me.Vector(0)
    torque = me.Vector(0)
    for item in [*collected.particles, *collected.bodies]:
        r_abs = r_O + item.position
        v = r_abs.dt(N)
        a = v.dt(N)
        kinetic += item.mass * v.dot(v) / 2
        potential += -item.mass * g.dot(r_abs)
        f_i = item.mass * (a - g)
        force += f_i
        torque += item.position.cross(f_i)
    for b in collected.bodies:
        w = b.frame.ang_vel_in(N)
        h = b.inertia.dot(w)
        kinetic += w.dot(h) / 2
        torque += h.dt(N)

    qf = [s for _, s in coords]
    n = len(qf)
    q = tuple(sp.Symbol(f"q{i}", real=True) for i in range(n))
    qd = tuple(sp.Symbol(f"qd{i}", real=True) for i in range(n))
    qdd = tuple(sp.Symbol(f"qdd{i}", real=True) for i in range(n))
    inputs, units, usyms, rule = [], [], [], {}
    # the time derivative of every plain symbol but qd: q -> qd, an input's derivative of
    # order r -> the next, or the input declared as its derivative (a derivative no input
    # supplies stays a Derivative, named below)
    dot: dict = {}
    for j, (sig, name, unit, derivatives) in enumerate(shared.inputs):
        orders = []
        for order, suffix, uunit in ((0, "", unit), (1, "_dot", f"{unit}/s"),
                                     (2, "_ddot", f"{unit}/s^2"))[:derivatives + 1]:
            sym = sp.Symbol(f"u{j}_{order}", real=True)
            rule[sig.diff(t, order) if order else sig] = sym
            inputs.append(name + suffix)
            units.append(uunit)
            usyms.append(sym)
            orders.append(sym)
        for order, sym in enumerate(orders):
            dot[sym] = orders[order + 1] if order + 1 < len(orders) else sig.diff(t, order + 1)
    for i, s in enumerate(qf):
        rule[s.diff(t, 2)] = qdd[i]
        rule[s.diff(t)] = qd[i]
        rule[s] = q[i]
        dot[q[i]] = qd[i]

    def plain(e: sp.Expr) -> sp.Expr:
        return e.xreplace(rule)

    # an input given as another's derivative (an angular acceleration beside the rate)
    dot = {s: plain(ds) for s, ds in dot.items()}

    if n:
        # Lagrange's equations on plain symbols: with P = dL/dqd,
        # d/dt P = (dP/dqd) qdd + sum over the other symbols s of (dP/ds) s' + dP/dt,
        # so M = dP/dqd and f = dL/dq - (the rest) - dR/dqd + Q (SymPy's LagrangesMethod
        # gives the same equations through substitutions that take minutes on a free bus)
        lagrangian = plain(kinetic - potential)
        P = [sp.diff(lagrangian, v) for v in qd]
        M = sp.Matrix(n, n, lambda i, k: sp.diff(P[i], qd[k]))
        rayleigh = plain(sp.Add(*collected.dissipation))
        f = []
        for i in range(n):
            rest = sp.Add(*[sp.diff(P[i], s) * ds for s, ds in dot.items()]) + sp.diff(P[i], t)
            f.append(sp.diff(lagrangian, q[i]) - rest - sp.diff(rayleigh, qd[i]))
        for coord, gen_force in collected.forces:
            f[qf.index(coord)] += plain(gen_force)
        f = sp.Matrix(f)
    else:
        M, f = sp.zeros(0, 0), sp.zeros(0, 1)

    axes = T
    if shared.transducer is not None:  # measured about its point, in its own axes
        point, axes = shared.transducer
        torque = torque - point.cross(force)
    outputs = (
        *[plain(c) for c in force.to_matrix(axes)],
        *[plain(c) for c in torque.to_matrix(axes)],
        plain(kinetic),
        plain(potential),
    )
    left = set().union(*(e.atoms(sp.Derivative, AppliedUndef) for e in (*M, *f, *outputs)))
    if left:
        named = {u: sp.Symbol(nm) for u, nm in zip(usyms, inputs)}
        left = sorted(str(e.xreplace(named)) for e in left)
        raise InputError(
            f"the equations of {model!r} need {', '.join(left)}, which no "
            "input supplies; declare more derivatives with `add_input(..., derivatives=...)`")
    names = tuple(p.name for p in model.parameters)
    return SymbolicModel(
        coordinates=tuple(name for name, _ in coords),
        q=q, qd=qd, qdd=qdd,
        inputs=tuple(inputs), input_units=tuple(units), u=tuple(usyms),
        parameters=names, p=tuple(psym[nm] for nm in names), t=t,
        mass_matrix=M, forcing=f,
        outputs=outputs, measured=tuple(rig.measured),
    )
