"""Regenerate docs/tank-modes.md: exact vs legacy vs seed (Table 8) for the 8-inch sphere.

Run: ``python docs/make_tank_table.py`` (writes docs/tank-modes.md next to this file).
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from pathlib import Path

from analogs.tank import Liquid, Sphere, predict

R = 0.1016
WATER = Liquid(998.2, 0.893e-6, "water")
FILLS = (0.6, 0.7, 0.8)
SEED = {  # seed Table 8, water
    "1st frequency [Hz]": (2.093, 2.289, 2.601),
    "1st mass [kg]": (1.338, 1.214, 0.898),
    "1st length [m]": (0.057, 0.047, 0.037),
    "1st hinge height [m]": (0.102, 0.104, 0.109),
    "1st wave/bob ratio": (1.448, 1.541, 1.635),
    "2nd frequency [Hz]": (3.666, 3.830, 4.149),
    "2nd mass [kg]": (0.048, 0.063, 0.066),
    "2nd length [m]": (0.018, 0.017, 0.014),
    "2nd hinge height [m]": (0.100, 0.100, 0.095),
    "2nd wave/bob ratio": (0.405, 0.506, 0.627),
    "fixed mass [kg]": (1.456, 2.161, 2.965),
    "fixed height [m]": (0.101, 0.100, 0.099),
    "fixed inertia [kg m^2]": (0.007, 0.010, 0.014),
    "damping [% crit.]": (0.703, 0.874, 1.217),
}


def values(p):
    m1, m2 = p.modes
    f = p.fixed_mass
    return (m1.frequency_hz, m1.mass, m1.length, m1.hinge_height, m1.amplitude_ratio,
            m2.frequency_hz, m2.mass, m2.length, m2.hinge_height, m2.amplitude_ratio,
            f.mass, f.height, f.inertia, 100 * m1.damping_ratio)


FILLS1 = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.99)
TABLE1 = {  # seed Table 1 (water): fixed mass and slosh mass (1st + 2nd mode), kg
    "fixed": (0.008, 0.064, 0.209, 0.476, 0.890, 1.456, 2.161, 2.965, 3.783, 4.356),
    "slosh": (0.114, 0.392, 0.738, 1.068, 1.303, 1.386, 1.277, 0.964, 0.479, 0.028),
}
WAVE = {"1st wave/bob ratio", "2nd wave/bob ratio"}


def _mark(legacy: float, seed: float, tol: float) -> str:
    """`ok` within the acceptance tolerance of issue 4, else the miss in printed units."""
    miss = abs(legacy - seed) / tol
    return "ok" if miss <= 1.0 + 1e-9 else f"**{miss:.2f} units**"


def main() -> str:
    ex = [values(predict(Sphere(R), fill=f, liquid=WATER, method="exact")) for f in FILLS]
    lg = [values(predict(Sphere(R), fill=f, liquid=WATER, method="legacy")) for f in FILLS]
    head = "| quantity | " + " | ".join(
        f"exact {int(100 * f)} % | legacy {int(100 * f)} % | seed {int(100 * f)} % | "
        f"legacy vs seed | legacy-exact {int(100 * f)} %" for f in FILLS) + " |"
    lines = [head, "|---" * (1 + 5 * len(FILLS)) + "|"]
    for k, (name, seed) in enumerate(SEED.items()):
        tol = 2e-3 if name in WAVE else (1e-3 * seed[0] if "damping" in name else 1e-3)
        cells = []
        for i in range(len(FILLS)):
            e, g = ex[i][k], lg[i][k]
            rel = 100 * (g - e) / e if e else float("nan")
            cells.append(f"{e:.4f} | {g:.4f} | {seed[i]:.3f} | {_mark(g, seed[i], tol)} | "
                         f"{rel:+.2f} %")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    lines += ["", "| fill | exact fixed [kg] | legacy fixed [kg] | seed fixed [kg] | "
              "exact slosh [kg] | legacy slosh [kg] | seed slosh [kg] | legacy vs seed |",
              "|---|---|---|---|---|---|---|---|"]
    for i, f in enumerate(FILLS1):
        pe = predict(Sphere(R), fill=f, liquid=WATER, method="exact")
        pl = predict(Sphere(R), fill=f, liquid=WATER, method="legacy")
        se = pe.modes[0].mass + pe.modes[1].mass
        sl = pl.modes[0].mass + pl.modes[1].mass
        sf, ss = TABLE1["fixed"][i], TABLE1["slosh"][i]
        ok = max(abs(pl.fixed_mass.mass - sf), abs(sl - ss)) <= 1e-3 + 1e-9
        lines.append(f"| {round(100 * f)} % | {pe.fixed_mass.mass:.4f} | "
                     f"{pl.fixed_mass.mass:.4f} | {sf:.3f} | {se:.4f} | {sl:.4f} | {ss:.3f} | "
                     f"{'ok' if ok else '**miss**'} |")
    return "\n".join(lines)


TEXT = """# Tank modes: exact vs legacy vs seed (8-inch sphere)

Sphere R = 0.1016 m, water (rho = 998.2 kg/m^3, nu = 0.893 cSt), g = 9.81 m/s^2, fills
as liquid depth / diameter. *exact* is `predict(..., method="exact")` (Ritz with solid
harmonics up to 75 % fill, graded axisymmetric finite elements above; the two agree to
better than 1e-5 in lambda and 1e-4 in masses/heights, see
`tests/analogs/tank/test_tank_modes.py`). *legacy* is `method="legacy"`: the SLOSH
code's Lomen trial functions and Dodge's analog formulas (conventions below). *seed* is
the SLOSH code output in the seed paper's Tables 8 and 1. "legacy vs seed" is `ok` when
within issue 4's acceptance tolerance (one unit of the last printed digit; 0.002 for wave
ratios; 0.1 % for damping), else the miss in those units. Regenerate with
`python docs/make_tank_table.py`.

{table}

## Legacy conventions (found, with the evidence)

The open re-implementation of the SLOSH code, SLOSH-ML (Georgia Tech LGST lab, "based on
the original algorithm developed by D.O. Lomen for NASA in the CR-230 report and
subsequently updated by F.T. Dodge at SwRI", following pp. 60-64 of Dodge's "The New
Dynamic Behavior of Liquids in Moving Containers"; files `functions/phi.m`, `Aint.m`,
`Bint.m`, `core.m`, `derivedparams.m`), gave the conventions. Each was checked against
all 56 numbers of Tables 1 and 8 at once:

1. **Trial functions.** With `R = r/a`, `Z = (z - h)/a` (`a` the free-surface radius,
   `h` the depth): `U_n = R^(2n-1)` for n = 1..5 -- functions of `r` only, *not*
   harmonic except `R` -- and `U = J1(xi_k R) exp(xi_k Z)` for k = 1..5, `xi_k` the zeros
   of `J1'`. Reading the first family as the odd solid harmonics `rho^(2n-1) P^1_(2n-1)`
   (the previous version of this mode) misses the 40 % fixed mass (0.477 kg), the 80 %
   first frequency and mass (2.595 Hz, 0.893 kg), the 90 % masses (by 0.012 kg), the 60 %
   2nd-mode wave ratio (0.410) and every hinge height. The non-harmonic set is
   legitimate: the method is Rayleigh-Ritz on the energy functional, which needs no
   harmonic trial functions.
2. **Matrices.** `A_mn = int (U_m,r U_n,r + U_m,z U_n,z + U_m U_n / r^2) r dr dz` over the
   liquid section, `B_mn = int_0^a U_m U_n r dr` over the free surface, `A c = lambda B c`.
3. **Quadrature and contour.** Converged Gauss rules on the exact sphere reproduce the
   tables. SLOSH-ML's masked 200 x 200 Simpson rule scatters the results by about one
   printed unit (at 100 steps nine numbers miss); coarse 1-D Simpson rules in depth
   move the 60 % 2nd mode *away* from the seed; SLOSH-ML's 19-segment polygonal
   8-inch sphere misses by up to 13 units, and the seed's liquid masses (2.842/3.438/3.929
   kg) are the exact sphere's. So the original quadrature is "accurate", not a coarse one.
4. **Analog formulas.** Slosh mass `rho pi lambda a_n^2 / b_n`, length `1/lambda`, wave/bob
   ratio `lambda U(a, h) a_n / b_n`, fixed mass and its height from the static centre of
   gravity: all as in the exact mode. **Hinge height** (Dodge): `H_n = L_n - h +
   2 S_n / (lambda_n a_n)`, `S_n = int_0^h z r_w(z) U_n(r_w(z), z) dz` along the wetted
   wall. For an exact mode it is the moment of the wall pressure: with the converged Ritz
   modes it returns the sphere's centre (0.1016 m, checked at 30-80 %), and for a
   flat-bottom cylinder it reduces analytically to SP-106's bob height
   `h - (2a/xi) tanh(xi h / 2a)`. With the ten trial functions, which satisfy the wall
   condition only weakly, it moves the hinges to 0.1024/0.1043/0.1088 m (mode 1) and
   0.0997/0.0995/0.0946 m (mode 2): the seed's 0.102/0.104/0.109 and 0.100/0.100/0.095.
   The fixed-mass height then uses the bob heights `H_n - L_n`, as SLOSH-ML does.
5. **Mode order.** SLOSH-ML sorts modes by `m_n L_n`; for the sphere this is the
   frequency order at every fill of Table 1.
6. **Fixed-mass inertia: inferred convention.** Neither the seed nor SLOSH-ML defines it.
   `I_0 = I_rigid(h_0) - sum m_n (h_n - h_0)^2` (frozen liquid about the fixed mass, minus
   the bobs as point masses) reproduces 0.007/0.010/0.014 kg m^2.

**What still misses** (both at 60 %, mode 2, pinned in
`tests/analogs/tank/test_tank_legacy.py`): frequency 3.6670 vs 3.666 Hz (+0.00105 Hz,
1.05 units) and wave/bob ratio 0.4074 vs 0.405 (1.2 units of 0.002); glycerine's
2nd-mode mass at 60 % (0.0610 vs 0.060 kg, not in the issue's list) is the same gap.
Printed at the table's precision (3.667, 0.407, 0.061) each is one printed unit from the
seed; the raw differences exceed the acceptance tolerance by 5e-5 Hz and 4e-4.

The seed's 60 % 2nd mode is neither the converged Lomen mode nor the exact one. Its
three liquid columns (masses 0.048/0.060/0.066 kg at rho 998.2/1260/1370, each rounded)
put the SLOSH code's water mass in [0.04772, 0.04793] kg: at or below the *exact*
0.04795 kg, where the Lomen basis gives 0.04834. Yet its wave ratio (0.405) lies only
14-21 % of the way from the Lomen 0.4074 to the exact 0.3936, and its frequency
30-90 % of the way from 3.6670 to the exact 3.6653 Hz. The 70/80 % 2nd modes match the
Lomen basis. Tried, none closing the gap without breaking other numbers:

* quadrature: Gauss 3-24 points per panel; SLOSH-ML's masked rectangular Simpson grid at
  50-400 steps (best: 300-400 steps, all but the 60 % wave ratio, 1.08 units);
* basis: 3-7 polynomial x 3-8 Bessel-exponential functions (at 60 % every split misses
  something: 5 x 6 fixes mode 2 and moves the 1st wave ratio out by 1.9 units);
  rounded or truncated `xi_k`; zeros of `J1` instead of `J1'`; the volume integrals of
  the non-harmonic terms replaced by boundary (Green's identity) integrals;
* arithmetic: the eigenproblem in single precision (no change after equilibration);
* gravity: both the water and the glycerine/corn-syrup columns need the 60 % `lambda_2`
  lower relative to the other five frequencies, so no single `g` per column closes it.

Scaling only the Bessel functions by 0.995-0.997 times the free-surface radius closes
60 %, but 80 % then needs 1.000 +/- 0.0005 (70 %: 0.998-1.001); the free-surface radius
of a polygonal sphere (12-36 segments) does not follow that pattern and no source gives
such a factor, so it is not used. The glycerine and corn-syrup frequency columns are
0.001-0.002 Hz below the water ones, consistent with those runs using g = 9.80 m/s^2
(all but the same 60 % 2nd mode); the water column matches g = 9.81.

## Where the legacy code is wrong, and by how much

* **Frequencies and slosh masses above half full.** Ten trial functions cannot represent
  the flow near the contact line once the wall overhangs the free surface. At 60 % the
  legacy first frequency is 0.1 % high and the first mass 0.2 % high; at 80 % the seed's
  first frequency (2.601 Hz) is 1.5 % above the converged 2.563 Hz and its first mass
  (0.898 kg) 2.8 % above the converged 0.873 kg; the fixed mass is correspondingly too
  small. In Table 1 the summed slosh mass at 90 % (0.479 kg) is 9 % above the converged
  0.438 kg.
* **Hinge heights.** For a sphere the wall pressure passes through the centre, so every
  pendulum hinge is exactly at the centre (0.1016 m); both exact solvers give that to
  1e-9. The seed's 0.104/0.109 m (mode 1) and 0.095 m (mode 2, 80 %) are Dodge's hinge
  formula evaluated with the truncated trial functions (above); at 99 % fill it puts
  the hinges 5-6 mm above the tank bottom.
* **Wave/bob amplitude ratio.** The converged ratio is lower than the legacy one by 1.3 %
  (60 %), 3.1 % (70 %) and 6.8 % (80 %) for mode 1, and by 3-12 % for mode 2: the truncated
  basis overestimates the wave at the wall. The 2nd-mode mass is 9 % high at 80 %.
* **Fixed-mass height and inertia** inherit the hinge error through the bob heights
  (0.0995 vs 0.1015 m at 80 %); the inertia convention is inferred (above). The
  potential-flow effective inertia of liquid in a sphere is close to zero; use the
  frozen convention only as the seed did, as a starting value.
* **Damping** comes from the SP-106 correlation and is independent of the modal solver;
  it reproduces Table 8 (water, glycerine, corn syrup) to better than 0.1 %.
"""


if __name__ == "__main__":
    out = Path(__file__).with_name("tank-modes.md")
    out.write_text(TEXT.replace("{table}", main()), encoding="utf-8")
    print(f"wrote {out}")
