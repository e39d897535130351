"""What the estimated input adds to a fit problem, per case: the carriage motion's start
spline and noise levels and the force's noise (:mod:`estimate.fitting.carriage`), and the
notes that say so. A step of :meth:`FitProblem.build
<estimate.fitting.problem.FitProblem.build>`."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from ..data.experiment import Experiment
from .carriage import CarriageInput, RecordNoise, carriage_input, record_noise
from .strategies import EstimatedInput, InputMode

__all__ = ["DISPLACEMENT_FLOOR", "input_estimation", "noise_notes"]

#: Floor of the displacement noise [m]: no lab measurement of a carriage's travel is known
#: to better than a micrometre, and a planned path (the command, smooth to 1e-7 m above
#: the band) is no measurement of the motion at all; its error (servo lag and ripple) shows
#: only in the fit (:mod:`estimate.fitting.balance` rescales it then).
DISPLACEMENT_FLOOR = 1e-6


def input_estimation(exps: Sequence[Experiment], mode: InputMode
                     ) -> tuple[tuple[CarriageInput | None, ...], tuple[RecordNoise | None, ...]]:
    """Per case, the carriage spline (measured lateral cases) and the force noise, when the
    input is estimated (``mode``); ``None`` otherwise."""
    if not isinstance(mode, EstimatedInput):
        return tuple(None for _ in exps), tuple(None for _ in exps)
    carriage, noise = [], []
    for e in exps:
        case = e.case
        if case.test.rig != "lateral" or case.force is None:
            carriage.append(None)
            noise.append(None)
        elif case.test.excitation == "measured":
            ci, rn = carriage_input(case.time, case.displacement, force=case.force,
                                    at_rest=case.test.starts_at_rest,
                                    motion_band_hz=case.test.motion_band_hz)
            if ci.displacement_noise < DISPLACEMENT_FLOOR:
                ci = replace(ci, displacement_noise=DISPLACEMENT_FLOOR)
            carriage.append(ci)
            noise.append(rn)
        else:  # crank: the motion is a parametric model; the force's noise weighs it
            carriage.append(None)
            noise.append(record_noise(case.time, case.force, 2 * case.crank.frequency))
    return tuple(carriage), tuple(noise)


def noise_notes(exps, carriage, noise) -> tuple[str, ...]:
    """What the estimated input did to each case (noise levels, spline, removed tones)."""
    notes = []
    for e, ci, rn in zip(exps, carriage, noise):
        if rn is None:
            continue
        cid = e.case.test.id
        fig = rn.figure
        text = (f"{cid}: force residuals weighed by the force noise {rn.force_noise:.3g} N ("
                + (fig.detail if fig is not None else "") + ")"
                + (f", displacement residuals by {ci.displacement_noise:.3g} m" if ci else ""))
        if ci is not None:
            text += (f"; carriage motion estimated (quintic spline, knots "
                     f"{1e3 * ci.spline.spacing:.3g} ms apart"
                     + (", at rest at the first sample)" if ci.at_rest else ")")
                     + ("; the displacement noise is not white (a drifting or integrated "
                        "displacement): its level is the start spline's misfit"
                        if ci.coloured_noise else ""))
        notes.append(text)
        for label, tones, unit in (("force", rn.tones, "N"),
                                   ("displacement", ci.displacement_tones if ci else (), "m")):
            if tones:
                notes.append(f"{cid}: removed {label} tones " + ", ".join(
                    f"{f:.4g} Hz ({a:.3g} {unit})" for f, a in tones))
    return tuple(notes)
