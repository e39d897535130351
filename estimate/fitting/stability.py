"""Bounds that keep the fit's RK4 steps stable: a rotor's spin-up rate within reach of one
sample step.

A rotor analog (:class:`analogs.Rotor`) couples to the tank by a viscous torque: its spin
relative to the tank decays at the rate ``damping / inertia`` [1/s]. The fit integrates it
with explicit RK4 steps of the sample interval ``h``, stable on a real eigenvalue only while
``h damping / inertia`` stays below ~2.8. Past it the simulation grows without bound; a rotor
whose relative spin dies out within a fraction of a sample step is not resolved by the record
either (it is a damper). A fit from a poor start can walk there: a 20 s spinning-rig record
(rotor and spherical pendulum, the bound multipliers starting at 1e-5) took the rotor's inertia
to 0.0004 kg m^2 under a damper of 0.13 N m s/rad by its ninth iteration, overflowed, and ended
``Invalid_Number_Detected``; bounded by ``h damping <= RK4_MARGIN inertia`` it converges in
21 iterations to the truth (inertia 0.01007 for 0.01, damper 0.0397 for 0.04).

The bound is linear in the two estimates, so IPOPT keeps it at every iterate of a start
inside it (the constraint's residual shrinks by ``1 - alpha`` at every step). :func:`fit`
adds it only when a solve overflowed (``Invalid_Number_Detected``) and solves again from the
same start: present in every fit, it changed IPOPT's path on a spinning-rig record that
converges without it (300 iterations instead of converging).
"""

from __future__ import annotations

from collections.abc import Sequence

from .budget import LinearBound

__all__ = ["RK4_MARGIN", "rotor_bounds"]

#: The largest ``h rate`` allowed (RK4 is stable below ~2.8 on a real eigenvalue).
RK4_MARGIN = 2.0


def rotor_bounds(cases, model, estimated: Sequence[str]) -> tuple[LinearBound, ...]:
    """``damping - RK4_MARGIN / h * inertia <= 0`` for every rotor of ``model`` whose inertia
    and damping are both among ``estimated`` (labels ``"r1.inertia"``), ``h`` the shortest
    sample interval of ``cases`` [s]."""
    from analogs import Rotor

    h = min(float(c.sample_interval) for c in cases)
    out = []
    for comp in model.components:
        inertia, damping = f"{comp.name}.inertia", f"{comp.name}.damping"
        if isinstance(comp, Rotor) and inertia in estimated and damping in estimated:
            rate = RK4_MARGIN / h
            out.append(LinearBound(
                ((damping, 1.0), (inertia, -rate)), 0.0,
                f"{damping} <= {rate:.4g} 1/s x {inertia} (the rotor's spin-up within "
                f"{RK4_MARGIN:g} RK4 steps of {h * 1e3:.4g} ms: a stable simulation)",
                stability=True))
    return tuple(out)
