"""The raw result every modal solver returns, before it is turned into analog parameters."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class RawModes:
    """Lateral (m = 1) sloshing modes ``phi = U(r, z) cos(theta)``, first ``n`` of them.

    All integrals are per unit of ``pi`` (the azimuthal factor is dropped) and each ``U``
    has an arbitrary scale; every quantity built from them is scale invariant.

    Attributes
    ----------
    lam : eigenvalues ``omega^2 / g`` in 1/m, ascending.
    a : ``integral_0^rs r^2 U dr`` over the free surface (m^3 [U]).
    b : ``integral_0^rs r U^2 dr`` over the free surface (m^2 [U]^2).
    u_wall : ``U`` at the contact line ``(r_s, depth)`` ([U]).
    moment : ``integral (z (U_r + U/r) - r U_z) r dr dz`` over the meridian section, the
        pitch angular momentum integral of the mode (m^3 [U]).
    size : basis size (Ritz) or number of unknowns (finite elements).
    """

    lam: np.ndarray
    a: np.ndarray
    b: np.ndarray
    u_wall: np.ndarray
    moment: np.ndarray
    size: int
