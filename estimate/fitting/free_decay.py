"""What a record whose carriage never moves determines: free decays.

The natural-frequency test stops the drive and records the liquid ringing down with the
carriage at rest (``[test] initial_state = "free"``: the liquid's state at the first sample
is estimated with the parameters). The force is then the liquid's alone: the record fixes
the modes' frequencies and damping and each swing's force amplitude, not the masses (a
rigid mass multiplies an acceleration the carriage does not have; a mode's mass only its
swing, which is estimated with it). Those masses are held at their start values, with a
note (:func:`rest_holds`), instead of being estimated along directions the data do not
determine: on a 12 s decay of an 8-inch sphere the fixed mass went to 2.6e5 kg, times the
carriage spline's noise-level acceleration.

Where the free state starts needs nothing special: with multiple shooting (or
collocation) every node's state is a decision variable tied to the force, and fits
started from a simulation at rest converged in 7-12 iterations on the decays and the
2 s window of ``tests/estimate/fitting/test_lab_records.py``, as fast as from a state read
off the record by least squares (tried and left out).
"""

from __future__ import annotations

from analogs.errors import InputError

from ..data.signals import motion_band

__all__ = ["rest_holds"]


def rest_holds(experiments, names: list[str]) -> tuple[list[str], list[str]]:
    """The masses among ``names`` (estimated parameters) that lateral records whose carriage
    never moves cannot determine, and a note saying why they are held (module docstring);
    nothing when a case's carriage moves, or is not measured.

    Raises
    ------
    InputError
        When such a record's liquid starts at rest too: nothing moves, nothing to fit.
    """
    if not experiments or any(e.case.test.rig != "lateral" or e.case.displacement is None
                              for e in experiments):
        return [], []
    if any(motion_band(e.case.time, e.case.displacement) is not None for e in experiments):
        return [], []
    still = [e.case for e in experiments if (e.case.test.initial_state or "rest") == "rest"]
    if still:
        ids = ", ".join(f"`{c.path.name}`" for c in still)
        raise InputError(f"{ids}: the carriage does not move (the displacement holds nothing "
                         "above its noise) and `[test] initial_state` is \"rest\": nothing "
                         "moves the liquid; for a free decay (the liquid swinging at the first "
                         "sample) give `[test] initial_state = \"free\"`")
    rigid = ("fixed.mass", "rig.dry_mass")
    moving = {c.split(".")[0] for e in experiments for c in e.derived.coordinates}
    held = [n for n in names if n in rigid or (n.endswith(".mass") and n.split(".")[0] in moving)]
    if not held:
        return [], []
    note = ("the carriage does not move in any case (free decays): the record determines "
            "the modes' frequencies and damping, not the masses; held at their start values: "
            + ", ".join(f"`{n}`" for n in held))
    return held, [note]
