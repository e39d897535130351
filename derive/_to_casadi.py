"""SymPy expressions -> CasADi SX functions (through ``lambdify`` with common-subexpression
elimination and a CasADi namespace). The mass matrix is solved numerically."""

from __future__ import annotations

import casadi as ca
import sympy as sp

from ._lagrange import OUTPUT_NAMES, SymbolicModel

__all__ = ["to_casadi"]

_NAMESPACE = {
    "sin": ca.sin, "cos": ca.cos, "tan": ca.tan, "asin": ca.asin, "acos": ca.acos,
    "atan": ca.atan, "atan2": ca.atan2, "sinh": ca.sinh, "cosh": ca.cosh, "tanh": ca.tanh,
    "exp": ca.exp, "log": ca.log, "sqrt": ca.sqrt, "Abs": ca.fabs, "sign": ca.sign,
    "pi": ca.pi, "Heaviside": lambda x: ca.if_else(x > 0, 1, ca.if_else(x < 0, 0, 0.5)),
}


def _translate(args: list[list[sp.Symbol]], exprs: list[sp.Expr], sx_args: list[ca.SX]) -> list[ca.SX]:
    if not exprs:
        return []
    fn = sp.lambdify(args, exprs, modules=[_NAMESPACE], cse=True, docstring_limit=0)
    out = fn(*[[x[i] for i in range(x.numel())] for x in sx_args])
    return [ca.SX(o) if not isinstance(o, ca.SX) else o for o in out]


def to_casadi(sym: SymbolicModel) -> dict[str, ca.Function]:
    """CasADi functions of a symbolic model.

    Returns ``rhs(x, u, p, t) -> xdot``, ``outputs(x, u, p, t) -> y``,
    ``mass_matrix(x, u, p, t) -> M`` and ``forcing(x, u, p, t) -> f``, with
    ``x = [q; qd]`` and ``y`` ordered as :data:`OUTPUT_NAMES`.
    """
    n, m, npar = len(sym.q), len(sym.u), len(sym.p)
    x = ca.SX.sym("x", 2 * n)
    u = ca.SX.sym("u", m)
    p = ca.SX.sym("p", npar)
    t = ca.SX.sym("t")
    qdd = ca.SX.sym("qdd", n)
    q, qd = x[:n], x[n:]
    base = [list(sym.q), list(sym.qd), list(sym.u), list(sym.p), [sym.t]]
    base_sx = [q, qd, u, p, t]
    if n:
        mm = _translate(base, list(sym.mass_matrix), base_sx)
        ff = _translate(base, list(sym.forcing), base_sx)
        M = ca.reshape(ca.vertcat(*mm), n, n).T  # SymPy flattens row-major
        f = ca.vertcat(*ff)
        acc = ca.solve(M, f)
    else:
        M, f, acc = ca.SX(0, 0), ca.SX(0, 1), ca.SX(0, 1)
    ys = _translate(base + [list(sym.qdd)], list(sym.outputs), base_sx + [qdd])
    y = ca.substitute(ca.vertcat(*ys), qdd, acc)
    xdot = ca.vertcat(qd, acc)
    names = ["x", "u", "p", "t"]
    return {
        "rhs": ca.Function("rhs", [x, u, p, t], [xdot], names, ["xdot"]),
        "outputs": ca.Function("outputs", [x, u, p, t], [y], names, ["y"]),
        "mass_matrix": ca.Function("mass_matrix", [x, u, p, t], [M], names, ["M"]),
        "forcing": ca.Function("forcing", [x, u, p, t], [f], names, ["f"]),
    }


def dependencies(fns: dict[str, ca.Function], parameters: tuple[str, ...]) -> dict[str, list[str]]:
    """Which parameters each output and the equations of motion depend on."""
    out: dict[str, list[str]] = {}
    p = ca.SX.sym("p", len(parameters))
    x = ca.SX.sym("x", fns["rhs"].size1_in(0))
    u = ca.SX.sym("u", fns["rhs"].size1_in(1))
    t = ca.SX.sym("t")
    xdot = fns["rhs"](x, u, p, t)
    y = fns["outputs"](x, u, p, t)
    nodes = {"eom": xdot, **{name: y[i] for i, name in enumerate(OUTPUT_NAMES)}}
    for key, expr in nodes.items():
        flags = ca.which_depends(expr, p, 1, False) if expr.numel() else [False] * len(parameters)
        out[key] = [parameters[i] for i, used in enumerate(flags) if used]
    return out
