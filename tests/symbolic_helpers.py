"""Helpers of the symbolic tests: derived equations written with functions of time."""

import sympy as sp


def as_functions(sym, names):
    """The coordinates of a derived model as functions of time called ``names``, and the
    rule that puts them into its equations (which use plain symbols)."""
    t = sym.t
    funcs = [sp.Function(n)(t) for n in names]
    rule = {}
    for i, f in enumerate(funcs):
        rule.update({sym.qdd[i]: f.diff(t, 2), sym.qd[i]: f.diff(t), sym.q[i]: f})
    return funcs, rule
