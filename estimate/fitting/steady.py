"""A case that starts in steady motion: its initial state tied to the relative equilibrium
of the analog under the rig motion at the first sample, as equality constraints of the NLP
(so the start follows the parameters while they are estimated)."""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np

from derive import DerivedModel
from derive.equilibrium import equilibrium_equations

from .transcription import Block

__all__ = ["steady_start"]


def steady_start(block: Block, dm: DerivedModel, p: ca.MX, theta: ca.MX, u0: np.ndarray,
                 t0: float, n_coefficients: int = 0) -> Block:
    """``block`` (transcribed with a free initial state) with ``nx`` more constraints: the
    generalized forces at zero rates vanish at the first sample (cyclic coordinates such as
    a rotor angle held at 0, :func:`derive.equilibrium.equilibrium_equations`) and the
    relative rates are zero. The constraint Jacobian blocks, when the transcription gives
    them, are extended with the rows' exact derivatives."""
    nq = len(dm.coordinates)
    x0 = block.X[:, 0]
    eq = equilibrium_equations(dm)
    rows = ca.vertcat(eq.residual(x0[:nq], ca.DM(u0), p, t0), x0[nq:])
    g = ca.vertcat(block.g, rows)
    if block.jac_w is None:
        return replace(block, g=g)
    jac_c = None
    if block.jac_c is not None:
        jac_c = ca.vertcat(block.jac_c, ca.MX(rows.numel(), n_coefficients))
    return replace(block, g=g, g_fast=ca.vertcat(block.g_fast, rows),
                   g_jac=ca.vertcat(block.g_jac, rows),
                   jac_theta=ca.vertcat(block.jac_theta, ca.jacobian(rows, theta)),
                   jac_w=ca.vertcat(block.jac_w, ca.jacobian(rows, block.w)), jac_c=jac_c)
