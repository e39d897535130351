"""`slosh tank`: predicted analog parameters for a tank, fill and liquid.

Wire-up: ``estimate.cli`` calls :func:`add_parser` on its subparsers and dispatches to
:func:`run` (set as the ``func`` default).
"""

from __future__ import annotations

import argparse

from analogs.errors import InputError
from analogs.tank import Capsule, Cylinder, Liquid, Sphere, predict

from ..outputs import Outputs, json_text

__all__ = ["add_parser", "run"]

_SHAPES = ("sphere", "cylinder", "capsule")


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``tank`` subcommand to an argparse subparsers object."""
    p = subparsers.add_parser(
        "tank", help="predict slosh analog parameters from tank geometry and fill",
        description="Lateral slosh modes of an axisymmetric tank as pendulums (SI units, "
                    "heights from the tank bottom).")
    p.add_argument("--shape", choices=_SHAPES, default="sphere", help="tank shape")
    p.add_argument("--radius", type=float, required=True, help="inside radius, m")
    p.add_argument("--length", type=float, default=None,
                   help="cylinder height, or capsule cylindrical length, m")
    fill = p.add_mutually_exclusive_group(required=True)
    fill.add_argument("--fill", type=float, help="liquid depth / tank height, in (0, 1)")
    fill.add_argument("--volume-fill", type=float, help="liquid volume / tank volume, in (0, 1)")
    p.add_argument("--density", type=float, default=998.2, help="kg/m^3 (default 998.2)")
    p.add_argument("--viscosity", type=float, default=1.004e-6,
                   help="kinematic viscosity, m^2/s (default 1.004e-6)")
    p.add_argument("--gravity", type=float, default=9.81, help="axial acceleration, m/s^2")
    p.add_argument("--method", choices=("exact", "legacy"), default="exact")
    p.add_argument("--modes", type=int, default=2, help="modes kept as pendulums (default 2)")
    p.add_argument("--diaphragm", action="store_true", help="flag a diaphragm tank")
    p.add_argument("--json", metavar="OUT.json", help="write the prediction as JSON")
    p.add_argument("--plot", metavar="OUT.png",
                   help="plot slosh/fixed mass and frequencies against fill")
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    p.set_defaults(run=run)


def _tank(args: argparse.Namespace):
    if args.shape == "sphere":
        return Sphere(args.radius)
    if args.length is None:
        raise InputError(f"`--length` (m) is required for --shape {args.shape}; got none.")
    if args.shape == "cylinder":
        return Cylinder(args.radius, args.length)
    return Capsule(args.radius, args.length)


def _plot(args: argparse.Namespace, tank, liquid: Liquid, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    fills = np.linspace(0.05, 0.95, 19)
    rows = [predict(tank, fill=float(f), liquid=liquid, gravity=args.gravity,
                    method=args.method, modes=args.modes) for f in fills]
    fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(6.4, 6.4))
    ax1.plot(100 * fills, [r.fixed_mass.mass for r in rows], "k-o", ms=3, label="fixed mass")
    ax1.plot(100 * fills, [sum(m.mass for m in r.modes) for r in rows], "b-s", ms=3,
             label="slosh mass (kept modes)")
    ax1.set_ylabel("mass [kg]")
    ax1.legend()
    for n in range(args.modes):
        ax2.plot(100 * fills, [r.modes[n].frequency_hz for r in rows], "-o", ms=3,
                 label=f"mode {n + 1}")
    ax2.set_ylabel("frequency [Hz]")
    ax2.set_xlabel("fill [% of tank height]")
    ax2.legend()
    ax1.set_title(f"{tank!r}, {args.method}")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def run(args: argparse.Namespace) -> int:
    """Run ``slosh tank``; returns the exit status (2 on bad input)."""
    outputs = Outputs(overwrite=args.overwrite)
    outputs.file("--json", args.json).file("--plot", args.plot).check()
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
            _plot(args, tank, liquid, paths["--plot"])
    return 0
