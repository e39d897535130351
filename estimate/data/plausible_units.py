"""Whether a lab file's channels read without a unit look like SI.

A MAT file carries no units, and a TDMS or HDF5 channel may not say its own: such a channel
is read as SI (m, N). A displacement recorded in mm or a force in lbf then gives a carriage
that moves metres and an analog that weighs a thousand times its liquid, and the fit fails
after hundreds of iterations without a word about units. These checks run on what was
read, before any fit, and say which unit the numbers look like:

* a displacement whose peak-to-peak exceeds :data:`MAX_STROKE` (a test rig's stroke is
  below it): "looks like mm";
* a force against the force the tank's predicted analog (:func:`analogs.tank.predict`:
  the fixed liquid and the container moving with the carriage, each slosh mode a damped
  pendulum) gives for the carriage acceleration (differentiated from the displacement, in
  the unit it looks like): the measured force's RMS over the predicted one is 0.76-1.06 on
  the bundled records; outside :data:`FORCE_RATIO_RANGE`, the force is named in the unit that
  brings it into range ("lbf", "kN", ...).

They warn (:class:`ImplausibleUnit`); the record is read as it is.

One check refuses a record, whatever its format: a sample rate too low for the tank's first
slosh mode (:func:`sampling_problem`), the times of a record written in ms read as s.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = ["CSV_FORCE_RATIO_RANGE", "FORCE_RATIO_RANGE", "MAX_STROKE", "MIN_SAMPLES_PER_PERIOD",
           "ImplausibleUnit", "linear_force", "sampling_problem", "unit_warnings"]

#: Largest plausible carriage peak-to-peak displacement [m]: lateral slosh rigs and robot
#: transport moves stay well below it.
MAX_STROKE = 2.0
#: Plausible range of the measured force's RMS over the RMS of the force the tank's
#: predicted analog gives for the same carriage acceleration: 0.76-1.06 on the bundled
#: records (sines near resonance, sweeps, two fills a mode apart), a prediction's
#: masses and damping being right to tens of per cent. A force in lbf read as N gives
#: 0.17-0.24, in kN 0.001. Without the container's mass (not weighed) the prediction is
#: too small and only a force below the range is judged.
FORCE_RATIO_RANGE = (0.4, 2.5)
#: The range for a CSV's force, SI by the format's definition: only a unit a factor of
#: about ten or more off is named (kN, mN, kgf), so that a record whose liquid sloshes far
#: harder or softer than ``[prediction]`` says (a drive at resonance, a damping ratio
#: guessed low) is not taken for one in lbf.
CSV_FORCE_RATIO_RANGE = (0.15, 7.0)
#: Carriage accelerations below this [m/s^2 peak-to-peak] do not judge a force (a carriage
#: at rest, a free decay).
MIN_ACCELERATION = 0.05
#: Fewest samples per period of the tank's first slosh mode a record may have: at 4 the mode
#: sits at half the Nyquist frequency, where the fit's start (a filter of the record) and
#: its low-passes still resolve it.
MIN_SAMPLES_PER_PERIOD = 4.0
#: Records sampled at this rate [Hz] or faster are not judged (no tank's first mode is near
#: a quarter of it), so the tank's prediction is not computed for them.
_RATE_JUDGED_BELOW = 40.0
#: Units a length or a force may have been recorded in, and their size in SI.
_LENGTHS = (("mm", 1e-3), ("cm", 1e-2), ("in", 0.0254))
_FORCES = (("lbf", 4.4482216152605), ("kN", 1e3), ("kgf", 9.80665), ("mN", 1e-3))


class ImplausibleUnit(UserWarning):
    """A lab file's channel read without a unit has numbers that do not look like SI."""


def _spread(x: np.ndarray) -> float:
    """Peak-to-peak between the 0.5 and 99.5 percentiles (a few spikes do not count)."""
    lo, hi = np.percentile(x, [0.5, 99.5])
    return float(hi - lo)


def _displacement_unit(ptp: float) -> tuple[str, float] | None:
    """The length unit that makes a peak-to-peak of ``ptp`` (read as m) a plausible stroke."""
    if ptp <= MAX_STROKE:
        return None
    for unit, size in _LENGTHS:
        if ptp * size <= MAX_STROKE:
            return unit, size
    return "mm", 1e-3


def _force_unit(ratio: float) -> str | None:
    """The force unit whose size brings the force ``ratio`` (read as N) into range, nearest
    to 1 on a log scale."""
    lo, hi = FORCE_RATIO_RANGE
    fits = [(abs(math.log(ratio * size)), unit) for unit, size in _FORCES
            if lo <= ratio * size <= hi]
    return min(fits)[1] if fits else None


def sampling_problem(name: str, time: np.ndarray, first_mode_hz) -> str | None:
    """The problem of a record sampled too slowly for the tank's first slosh mode, or None.

    Parameters
    ----------
    name : str
        The data file's name, for the message.
    time : ndarray
        The sample times as read [s].
    first_mode_hz : callable
        Returns the first mode's frequency [Hz] (``[prediction]``'s pendulum or the tank's
        modal analysis), or None when it cannot be predicted; called only for a record
        sampled below :data:`_RATE_JUDGED_BELOW`.

    Examples
    --------
    >>> t = np.arange(0.0, 30001.0, 10.0)                # 100 Hz samples written in ms
    >>> sampling_problem("A1.csv", t, lambda: 2.09)[:60]
    'A1.csv: column `time`: a step of 10 s (0.1 Hz) gives 0.048 s'
    >>> sampling_problem("A1.csv", t / 1000, lambda: 2.09) is None
    True
    """
    t = np.asarray(time, float)
    if t.size < 2:
        return None
    step = float(np.median(np.diff(t)))
    if not (step > 0 and math.isfinite(step)) or 1.0 / step >= _RATE_JUDGED_BELOW:
        return None
    f1 = first_mode_hz()
    if f1 is None or not (f1 > 0 and math.isfinite(f1)):
        return None
    per_period = 1.0 / (step * f1)
    if per_period >= MIN_SAMPLES_PER_PERIOD:
        return None
    text = (f"{name}: column `time`: a step of {step:.3g} s ({1 / step:.3g} Hz) gives "
            f"{per_period:.2g} samples per period of the tank's first slosh mode "
            f"({f1:.3g} Hz predicted), at least {MIN_SAMPLES_PER_PERIOD:g} are needed to fit it")
    if 1e3 * per_period >= MIN_SAMPLES_PER_PERIOD:
        text += f": the times look like ms (a step of {step:.3g} ms); give them in s"
    return text


def linear_force(time: np.ndarray, acceleration: np.ndarray, rigid_mass: float,
                 modes: Sequence[tuple[float, float, float]]) -> np.ndarray:
    """The lateral force [N] of a rigid mass and linear pendulums under the carriage
    ``acceleration`` [m/s^2] (uniform ``time``, s), by FFT: each mode ``(mass kg, omega
    rad/s, damping ratio)`` adds ``m (w_n^2 + 2i z w_n w) / (w_n^2 - w^2 + 2i z w_n w)`` to the
    rigid mass (its bob's acceleration over the carriage's, from the linearised pendulum).

    Examples
    --------
    >>> t = np.linspace(0, 20, 2001)
    >>> a = np.sin(2 * np.pi * 0.5 * t)          # far below the mode: the bob follows
    >>> f = linear_force(t, a, 1.0, [(2.0, 2 * np.pi * 5.0, 0.01)])
    >>> bool(np.allclose(f[500:1500], 3.0 * a[500:1500], rtol=0, atol=0.05))
    True
    """
    n = time.size
    w = 2 * np.pi * np.fft.rfftfreq(n, float(np.median(np.diff(time))))
    h = np.full(w.shape, complex(rigid_mass))
    for mass, wn, zeta in modes:
        z = 0.01 if not math.isfinite(zeta) else zeta
        h += mass * (wn**2 + 2j * z * wn * w) / (wn**2 - w**2 + 2j * z * wn * w)
    return np.fft.irfft(h * np.fft.rfft(acceleration), n)


def unit_warnings(name: str, unitless: Sequence[str], time: np.ndarray,
                  displacement: np.ndarray | None, force: np.ndarray | None, *,
                  rigid_mass: float, modes: Sequence[tuple[float, float, float]] = (),
                  weighed: bool = True, channels: dict[str, str] | None = None,
                  csv: bool = False, acceleration: np.ndarray | None = None) -> list[str]:
    """What looks wrong about the channels read without a unit (``unitless``: column names).

    Parameters
    ----------
    name : str
        The data file's name, for the messages.
    unitless : sequence of str
        The columns read with no unit from ``[data.columns]`` or the file (read as SI).
    time, displacement, force : ndarray
        The samples as read [s, m, N] (``displacement`` None for a crank drive).
    rigid_mass : float
        The mass that moves rigidly with the carriage [kg]: the predicted fixed liquid, plus
        the container when weighed.
    modes : sequence of (float, float, float), default ()
        The predicted slosh modes: mass [kg], natural frequency [rad/s], damping ratio.
    weighed : bool, default True
        Whether ``rigid_mass`` holds the container (else the predicted force is a lower
        bound, and a force above it is not judged).
    channels : dict, optional
        The file's channel of each column, for the messages.
    csv : bool, default False
        The columns are a CSV file's, SI by the format's definition: the messages ask for
        the column in SI instead of a unit in ``[data.columns]``.
    acceleration : ndarray, optional
        The carriage acceleration [m/s^2] differentiated from ``displacement`` as read, when
        the caller has it (used when the displacement looks like SI).

    Examples
    --------
    >>> t = np.linspace(0, 10, 1001)
    >>> x = 3.0 * np.sin(2 * np.pi * t)               # 3 mm read as 3 m
    >>> unit_warnings("A1.mat", ["displacement"], t, x, None, rigid_mass=4.0)[0][:60]
    'A1.mat: channel `displacement` ([data.columns] displacement)'
    """
    channels = channels or {}
    out = []

    def where(column: str) -> str:
        if csv:
            return f"{name}: column `{column}` (a CSV's columns are SI)"
        return f"{name}: channel `{channels.get(column, column)}` ([data.columns] {column})"

    def unit_hint(column: str, unit: str, si: str, shown: str = "") -> str:
        if csv:
            return f"looks like {unit}{shown}; write it in {si}"
        return (f"looks like {unit}{shown}; give its unit in [data.columns] (`{column} = "
                f'{{ channel = "{channels.get(column, "...")}", unit = "{unit}" }}`)')

    scale = 1.0
    if "displacement" in unitless and displacement is not None:
        ptp = _spread(displacement)
        guess = _displacement_unit(ptp)
        if guess is not None:
            unit, scale = guess
            out.append(f"{where('displacement')} {'reads' if csv else 'has no unit and'} a "
                       f"peak-to-peak of {ptp:.3g} m, more than a test rig moves "
                       f"({MAX_STROKE:g} m): "
                       f"{unit_hint('displacement', unit, 'm', f' ({ptp:.3g} {unit})')}")
    if "force" in unitless and force is not None and displacement is not None:
        from .signals import displacement_derivatives

        acc = acceleration if scale == 1.0 else None
        if acc is None:
            try:
                acc = displacement_derivatives(time, np.asarray(displacement) * scale)[2]
            except Exception:  # noqa: BLE001 - a record the smoother cannot take: not judged
                return out
        if _spread(acc) < MIN_ACCELERATION:
            return out
        predicted = linear_force(time, acc, rigid_mass, modes)
        ratio = float(np.std(force) / np.std(predicted))
        lo, hi = CSV_FORCE_RATIO_RANGE if csv else FORCE_RATIO_RANGE
        if ratio < lo or (weighed and ratio > hi):
            unit = _force_unit(ratio)
            hint = unit_hint("force", unit, "N") if unit else "check its unit and scale"
            basis = " (the displacement in its likely unit)" if scale != 1.0 else ""
            out.append(f"{where('force')} {'has an RMS' if csv else 'has no unit, and its RMS is'} "
                       f"{ratio:.3g} times what the "
                       f"tank's predicted analog gives for the carriage acceleration{basis} "
                       f"(plausible: {lo:g}-{hi:g}): {hint}")
    return out
