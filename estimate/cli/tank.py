"""`slosh tank`: predicted analog parameters for a tank, fill and liquid.

Wire-up: ``estimate.cli`` calls :func:`add_parser` on its subparsers and dispatches to
:func:`run` (set as the ``func`` default).
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from analogs.errors import InputError

from ..outputs import Outputs, json_text

if TYPE_CHECKING:
    from analogs.tank import Liquid

__all__ = ["add_parser", "run"]

_SHAPES = ("sphere", "cylinder", "capsule", "rectangular")


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``tank`` subcommand to an argparse subparsers object."""
    p = subparsers.add_parser(
        "tank", help="predict slosh analog parameters from tank geometry and fill",
        description="Lateral slosh modes of an axisymmetric tank as pendulums (SI units, "
                    "heights from the tank bottom); an upright rectangular tank in closed form.")
    p.add_argument("--shape", choices=_SHAPES, default="sphere", help="tank shape")
    p.add_argument("--radius", type=float, default=None,
                   help="inside radius, m (sphere, cylinder, capsule)")
    p.add_argument("--length", type=float, default=None,
                   help="cylinder height, capsule cylindrical length, or rectangular tank's "
                        "length along the motion, m")
    p.add_argument("--width", type=float, default=None,
                   help="rectangular tank: inside width across the motion, m")
    p.add_argument("--height", type=float, default=None,
                   help="rectangular tank: inside height, m")
    fill = p.add_mutually_exclusive_group(required=True)
    fill.add_argument("--fill", type=float, help="liquid depth / tank height, in (0, 1)")
    fill.add_argument("--volume-fill", type=float, help="liquid volume / tank volume, in (0, 1)")
    p.add_argument("--density", type=float, default=998.2, help="kg/m^3 (default 998.2)")
    p.add_argument("--viscosity", type=float, default=1.004e-6,
                   help="kinematic viscosity, m^2/s (default 1.004e-6)")
    p.add_argument("--gravity", type=float, default=9.81,
                   help="axial acceleration, m/s^2 (default 9.81)")
    p.add_argument("--method", choices=("exact", "legacy"), default="exact",
                   help="exact: the modal analysis converged to the tank's own shape (Ritz or "
                        "finite elements, default); legacy: the SLOSH code's Lomen basis, for "
                        "comparison with its tables (not converged above half full)")
    p.add_argument("--modes", type=int, default=2, help="modes kept as pendulums (default 2)")
    p.add_argument("--diaphragm", action="store_true",
                   help="the tank has a diaphragm: the prediction stays the free-surface one "
                        "and a note says what a diaphragm changes (a higher frequency, a "
                        "smaller slosh mass, more damping: fit them)")
    p.add_argument("--json", metavar="OUT.json", help="write the prediction as JSON")
    p.add_argument("--plot", metavar="OUT.png",
                   help="plot slosh/fixed mass and frequencies against fill")
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    p.set_defaults(run=run)


def _tank(args: argparse.Namespace):
    from analogs.tank import Capsule, Cylinder, Rectangular, Sphere

    needed = (("length", "width", "height") if args.shape == "rectangular"
              else ("radius",) if args.shape == "sphere" else ("radius", "length"))
    missing = [f"`--{k}`" for k in needed if getattr(args, k) is None]
    stray = [f"`--{k}`" for k in ("radius", "length", "width", "height")
             if k not in needed and getattr(args, k) is not None]
    if missing or stray:
        raise InputError(f"--shape {args.shape} takes " + ", ".join(f"`--{k}`" for k in needed)
                         + " (m); " + (f"got none for {', '.join(missing)}" if missing else
                                       f"{', '.join(stray)} does not apply"))
    if args.shape == "rectangular":
        return Rectangular(args.length, args.width, args.height)
    if args.shape == "sphere":
        return Sphere(args.radius)
    if args.shape == "cylinder":
        return Cylinder(args.radius, args.length)
    return Capsule(args.radius, args.length)


#: Legacy Lomen basis: where the prediction's note says it has not converged (fill above).
_LEGACY_CONVERGED_UP_TO = 0.5


def _spans(x, flag) -> list[tuple[float, float]]:
    """Contiguous ranges of ``x`` (uniform) where ``flag`` holds, widened by half a step."""
    import numpy as np

    step = float(np.median(np.diff(x))) if len(x) > 1 else 1.0
    edges = np.flatnonzero(np.diff(np.r_[0, np.asarray(flag, int), 0]))
    return [(float(x[a]) - step / 2, float(x[b - 1]) + step / 2) for a, b in zip(edges[::2], edges[1::2])]


def _label_beside_curve(ax, x: float, y: float, text: str, xs, ys, *, low: bool) -> None:
    """Write ``text`` beside the point ``(x, y)`` of the curve ``(xs, ys)`` where the curve
    leaves room (a label level with the point lay on a flat curve): below it on the right
    where the curve rises or stays level to the right of ``x``, above it on the right where
    it falls; ``low`` (the point near the bottom of the axis): above it, on the left of a
    rising curve."""
    import numpy as np

    xs, ys = np.asarray(xs, float), np.asarray(ys, float)
    right = ys[xs > x][:2]
    falls = right.size > 0 and bool(np.nanmax(right) < y)
    above = falls or low
    left = low and not falls
    ax.annotate(text, (x, y), xytext=(-6 if left else 6, 6 if above else -6),
                textcoords="offset points", ha="right" if left else "left",
                va="bottom" if above else "top", color="#b2182b", fontsize="small",
                gid="requested fill label")


def _plot(args: argparse.Namespace, tank, liquid: Liquid, path: str, pred) -> None:
    import numpy as np
    from matplotlib.figure import Figure

    from analogs.tank import predict

    from .. import _plotting as style
    from .._progress import progress

    fills = np.linspace(0.05, 0.95, 19)
    rows = []
    with progress(total=fills.size, desc="tank plot", unit="fill") as bar:
        for f in fills:
            rows.append(predict(tank, fill=float(f), liquid=liquid, gravity=args.gravity,
                                method=args.method, modes=args.modes))
            bar.update()
    pct = 100 * fills
    fig = Figure(figsize=(7.5, 8.5), layout="constrained")
    ax = fig.subplots(3, 1, sharex=True, height_ratios=[1.2, 1, 0.8])
    ax[0].plot(pct, [r.liquid_mass for r in rows], color="0.6", ls=":", lw=1.2, label="liquid mass")
    ax[0].plot(pct, [r.fixed_mass.mass for r in rows], "k-o", ms=3, label="fixed mass")
    for n in range(args.modes):
        ax[0].plot(pct, [r.modes[n].mass for r in rows], "-s", ms=3, color=f"C{n}",
                   label=f"slosh mass, mode {n + 1}")
        ax[1].plot(pct, [r.modes[n].frequency_hz for r in rows], "-s", ms=3, color=f"C{n}",
                   label=f"mode {n + 1}")
    ax[0].set_ylabel("mass [kg]")
    ax[1].set_ylabel("frequency [Hz]")
    zeta = np.array([r.modes[0].damping_ratio for r in rows])
    ax[2].plot(pct, zeta, "-o", ms=3, color="C2", label="damping ratio (all modes)")
    ax[2].set(ylabel="damping ratio [-]", xlabel="fill [% of tank height]", xlim=(0, 100))
    if not np.any(np.isfinite(zeta)):  # a rectangular tank or a general profile
        ax[2].text(0.5, 0.5, f"no damping correlation for a {args.shape} tank",
                   transform=ax[2].transAxes, ha="center", va="center", color="0.4")
    # what the reader should not trust: the legacy basis above half full, damping outside
    # its correlation's data
    if args.method == "legacy":
        for a in ax[:2]:
            a.axvspan(100 * _LEGACY_CONVERGED_UP_TO, 100, **style.DISCOUNT,
                      label="legacy basis not converged")
    invalid = np.array([any("validity range" in n for n in r.notes) for r in rows])
    for i, (lo, hi) in enumerate(_spans(pct, invalid)):
        ax[2].axvspan(lo, hi, **style.DISCOUNT, label="outside the correlation's data" if i == 0 else None)
    # the requested fill, with the prediction there
    req = 100 * pred.fill_fraction
    for i, a in enumerate(ax):
        a.axvline(req, color="#b2182b", lw=1.2, ls="--", gid="requested fill",
                  label=f"requested fill {req:.3g} %" if i == 0 else None)
    ax[0].plot([req] * (1 + args.modes), [pred.fixed_mass.mass, *(m.mass for m in pred.modes)], "D",
               color="#b2182b", ms=6, zorder=4)
    ax[1].plot([req] * args.modes, [m.frequency_hz for m in pred.modes], "D", color="#b2182b", ms=6,
               zorder=4)
    curves = np.array([[r.modes[n].frequency_hz for r in rows] for n in range(args.modes)])
    lo, hi = float(np.nanmin(curves)), float(np.nanmax(curves))
    for n, mode in enumerate(pred.modes):
        low = mode.frequency_hz - lo < 0.15 * (hi - lo)  # room for the text below it?
        _label_beside_curve(ax[1], req, mode.frequency_hz, f"{mode.frequency_hz:.3g} Hz", pct,
                            curves[n], low=low)
    # volume fill on the top axis (monotone in the height fill)
    grid = np.linspace(0.0, 1.0, 401)
    vol = np.array([tank.volume(g * tank.height) for g in grid]) / tank.volume()
    top = ax[0].secondary_xaxis("top", functions=(lambda x: 100 * np.interp(x / 100, grid, vol),
                                                  lambda v: 100 * np.interp(v / 100, vol, grid)))
    top.set_xlabel("fill [% of tank volume]")
    for a in ax:
        a.legend(loc="best", fontsize="small")
    size = (f"{args.length:g} x {args.width:g} m" if args.shape == "rectangular"
            else f"radius {args.radius:g} m")
    fig.suptitle(f"{args.shape}, {size}, height {tank.height:.4g} m\n"
                 f"{liquid.density:g} kg/m^3, g = {args.gravity:g} m/s^2, method {args.method}",
                 fontsize="medium")
    fig.savefig(path, dpi=120)
    return fig


#: Unit of each numeric option (ranges: :data:`estimate.data.case.PHYSICAL_RANGES`).
_UNITS = {"radius": "m", "length": "m", "width": "m", "height": "m", "density": "kg/m^3",
          "viscosity": "m^2/s", "gravity": "m/s^2"}


def _check_ranges(args: argparse.Namespace) -> None:
    """Options outside the physical ranges a case file's keys have (``--radius 1e300``)."""
    from ..data._toml import range_problem

    problems = []
    for name, unit in _UNITS.items():
        value = getattr(args, name, None)
        if value is not None and value == value:  # NaN: the tank module's own check says it
            why = range_problem(value, unit, positive=True)
            if why:
                problems.append(f"--{name} {value:g}: {why}")
    if problems:
        raise InputError("; ".join(problems))


def run(args: argparse.Namespace) -> int:
    """Run ``slosh tank``; returns the exit status (2 on bad input)."""
    from analogs.tank import Liquid, predict

    outputs = Outputs(overwrite=args.overwrite)
    outputs.file("--json", args.json).file("--plot", args.plot).check()
    _check_ranges(args)
    try:
        tank = _tank(args)
        liquid = Liquid(density=args.density, viscosity=args.viscosity, name="liquid")
        pred = predict(tank, fill=args.fill, volume_fill=args.volume_fill, liquid=liquid,
                       gravity=args.gravity, method=args.method, modes=args.modes,
                       diaphragm=args.diaphragm)
    except ValueError as err:  # the tank module's checks of its arguments
        raise InputError(str(err)) from None
    print(pred.report())
    with outputs.writing() as paths:
        if args.json:
            paths["--json"].write_text(json_text({**pred.to_dict(), "notes": list(pred.notes)}))
        if args.plot:
            _plot(args, tank, liquid, paths["--plot"], pred)
    return 0
