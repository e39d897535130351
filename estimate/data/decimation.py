"""A record decimated for the fit: ``[test] decimate = k``.

Rigs sample at 500 Hz to a few kHz; slosh modes lie below about 10 Hz and a carriage's motion
a little above. The samples above a few tens of Hz hold only noise, and every one of them
costs the fit time and memory (``estimate/data/budget.py``). ``[test] decimate = k`` keeps
every ``k``-th sample after an anti-alias low-pass: an order-8 Butterworth filter whose
half-power frequency is 0.8 times the new Nyquist frequency (0.4 times the new rate), run
forward and backward (:func:`scipy.signal.sosfiltfilt`), so no channel is shifted in time and
all keep their relative timing. Its gain is 1 to within 1e-9 below a tenth of the new rate
(the slosh band) and to within 5e-4 below a quarter. A Chebyshev filter (SciPy's
:func:`scipy.signal.decimate`) was not taken: its passband ripple, 0.989 at low frequencies
forward and backward, scales the motion and the force alike, which a linear model absorbs but
a swing-dependent one does not (the 0.25 rad swings of a 60 s sweep fitted after it put the
pendulum length 13 standard errors off). Inside the passband the noise is unchanged, so the
estimates lose no information the model can use; their intervals are computed from the
decimated residuals as from any record, the noise spectrum read below :data:`FLAT` of the new
rate (:func:`noise_band`), where the filter has not taken the noise away.

Where the residual is model error rather than noise (a transport record's residual is 5
times its noise) the low-pass leaves it while fewer samples remain, so the intervals widen
with the factor (measured: the container's and the stream lag's 1.5-2.7 times at 5): decimate
records the model explains, or keep every sample where the last digit of precision matters.

The new rate must keep the slosh band well inside the passband: at least
:data:`MIN_RATE_HZ`, and the passband above ``[test] motion_band_hz`` when that is given.

Without the key, ``slosh fit`` and a campaign's fits decimate a long lateral record sampled
far above the slosh band to about :data:`NOTE_RATE_HZ` (:func:`slosh_band_decimated`,
``[test] decimate = 1`` or ``--decimate 1`` keeps every sample; measured, the intervals
came out the same to 5 % or wider, and a 10-minute, 1 kHz record fits in 1 GB instead of
5), and the
diagnosis searches such a record decimated and fits its baseline and final model on every
sample (:func:`estimate.diagnosis.search.diagnose`). The Python ``fit()`` fits a case as it
is and says in its notes by how much to decimate (:func:`decimation_note`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["FLAT", "MIN_RATE_HZ", "MIN_SAMPLES", "NOTE_RATE_HZ", "NOTE_SAMPLES", "ORDER",
           "PASSBAND", "READ_ALLOWANCE", "angle_columns", "decimate_arrays", "decimate_case",
           "decimate_record", "decimation_note", "noise_band", "slosh_band_decimated",
           "slosh_band_factor"]

#: Lowest rate a record may be decimated to [Hz] (a passband to 16 Hz).
MIN_RATE_HZ = 40.0
#: The anti-alias filter's half-power frequency as a fraction of the new rate (0.8 of the
#: new Nyquist frequency).
PASSBAND = 0.4
#: The anti-alias Butterworth filter's order.
ORDER = 8
#: The band (a fraction of the new rate) where the forward and backward filter passes at least
#: 95 % of the noise's power: its gain is ``1 / (1 + (tan(pi f / fs) / tan(pi fc / fs))^16)``
#: (``fs`` the record's rate, ``fc`` the half-power frequency), 0.98 or more there.
FLAT = 0.3
#: A record of at least this many samples at twice :data:`NOTE_RATE_HZ` or more is told that
#: decimating would fit it faster (:func:`decimation_note`): from a 20 s, 500 Hz record on,
#: the fit takes half the time or less decimated to 100 Hz.
NOTE_SAMPLES = 10_000
#: The rate :func:`decimation_note` proposes [Hz].
NOTE_RATE_HZ = 100.0
#: Fewest samples a decimated record keeps.
MIN_SAMPLES = 100


def decimate_record(name: str, time: np.ndarray, columns: dict[str, np.ndarray], factor: int,
                    problems: list[str], motion_band_hz: float | None = None,
                    angles: frozenset[str] = frozenset(), what: str = "[test] decimate ="
                    ) -> tuple[np.ndarray, dict[str, np.ndarray], str] | None:
    """``time`` and every channel of ``columns`` decimated by ``factor`` (``name``: the data
    file, for the messages), and a note of what was done; ``None`` (with the reasons in
    ``problems``) when the record cannot be decimated soundly. ``time`` is uniform [s]. The
    columns named in ``angles`` (a spinning table's measured angle and nutation phase, rad)
    are unwrapped first: filtered across a wrap from pi to -pi they would be wrong for a
    filter's length, and they come back continuous. ``what`` names the request in the
    messages (``--decimate`` from the command line)."""
    from scipy.signal import butter, sosfiltfilt

    from .budget import _ordinal

    where = f"{name}: {what} {factor}"
    if factor == 1:
        return time, columns, ""
    rate = 1.0 / float(np.median(np.diff(time)))
    new_rate = rate / factor
    found = len(problems)
    if new_rate < MIN_RATE_HZ:
        problems.append(f"{where}: the record's {rate:.6g} Hz would become {new_rate:.3g} Hz; "
                        f"expected at least {MIN_RATE_HZ:g} Hz (a passband to "
                        f"{PASSBAND * MIN_RATE_HZ:g} Hz, above the slosh modes and the "
                        f"carriage's motion): decimate by at most "
                        f"{max(int(rate // MIN_RATE_HZ), 1)}")
    elif motion_band_hz is not None and motion_band_hz > PASSBAND * new_rate:
        problems.append(f"{where}: the passband would end at {PASSBAND * new_rate:.3g} Hz, "
                        f"below [test] motion_band_hz = {motion_band_hz:g} Hz; decimate by at "
                        f"most {max(int(PASSBAND * rate // motion_band_hz), 1)}")
    if time.size // factor < MIN_SAMPLES:
        problems.append(f"{where}: {time.size} samples would become {time.size // factor}; "
                        f"expected at least {MIN_SAMPLES}")
    bad = [k for k, v in columns.items() if not np.all(np.isfinite(v))]
    if bad:
        problems.append(f"{where}: channel{'s' if len(bad) > 1 else ''} "
                        f"{', '.join(f'`{k}`' for k in bad)} hold non-finite values; the "
                        "anti-alias filter needs every sample")
    if len(problems) > found:
        return None
    sos = butter(ORDER, 2 * PASSBAND / factor, output="sos")  # of the record's Nyquist
    out = {k: np.ascontiguousarray(sosfiltfilt(sos, np.unwrap(np.asarray(v, float))
                                               if k in angles else np.asarray(v, float))[::factor])
           for k, v in columns.items()}
    kept = time[::factor].copy()
    note = (f"{name}: decimated by {factor} for the fit ({what.rstrip(' =')}): {rate:.6g} -> "
            f"{new_rate:.6g} Hz, {time.size} -> {kept.size} samples; every channel low-passed "
            f"below {PASSBAND * new_rate:.3g} Hz forward and backward (no shift between "
            f"channels), then every {factor}{_ordinal(factor)} sample kept")
    return kept, out, note


def angle_columns(rig) -> frozenset[str]:
    """The columns of ``rig``'s measured spin motion that hold angles (rad, unwrapped before
    the low-pass): ``[rig.spin] spin_angle`` and ``nutation_phase``."""
    spin = getattr(rig, "spin", None)
    if spin is None:
        return frozenset()
    return frozenset(col for key, col in spin.columns.items()
                     if key in ("spin_angle", "nutation_phase"))


def noise_band(case) -> float:
    """The highest frequency (cycles per sample) at which ``case``'s record holds its noise
    as it was measured: 0.5 (Nyquist), or :data:`FLAT` when the record was decimated."""
    factor = getattr(case.test, "decimate", None)
    return FLAT if factor and factor > 1 else 0.5


def decimate_arrays(name: str, arrays: tuple, factor: int, problems: list[str],
                    motion_band_hz: float | None, rig, what: str = "[test] decimate ="
                    ) -> tuple[tuple, str] | None:
    """:func:`decimate_record` of a record as the case reader holds it, ``(time,
    displacement, force, columns)`` (``displacement`` and ``force`` may be ``None``;
    ``rig``'s angle columns unwrapped), in the same form, and what was done."""
    time, disp, force, columns = arrays
    named = {"displacement": disp, "force": force, **columns}
    out = decimate_record(name, time, {k: v for k, v in named.items() if v is not None},
                          factor, problems, motion_band_hz, angle_columns(rig), what)
    if out is None:
        return None
    kept, ch, note = out
    return (kept, ch.get("displacement"), ch.get("force"), {k: ch[k] for k in columns}), note


def decimate_case(case, factor: int, what: str = "decimate"):
    """``case`` with its record decimated by ``factor`` (as ``[test] decimate = factor``
    would have read it; ``what`` names the request in the messages, e.g. ``--decimate``;
    ``factor`` 1: every sample, said by ``[test] decimate = 1``, which
    :func:`slosh_band_factor` leaves alone). Raises :class:`~estimate.data.case.CaseError`
    when the record cannot take it or is decimated already."""
    from dataclasses import replace

    from .case import CaseError

    if case.test.decimate and case.test.decimate > 1:
        raise CaseError([f"{case.path.name}: {what} {factor}: the case decimates its record "
                         f"by {case.test.decimate} already ([test] decimate); give one of them"])
    if factor == 1:  # every sample asked for: said, so nothing decimates it later
        return replace(case, test=replace(case.test, decimate=1))
    problems: list[str] = []
    out = decimate_arrays(case.data_path.name, (case.time, case.displacement, case.force,
                                                dict(case.columns)),
                          factor, problems, case.test.motion_band_hz, case.rig, what)
    if out is None:
        raise CaseError(problems)
    (kept, disp, force, columns), note = out
    for arr in (kept, disp, force, *columns.values()):
        if arr is not None:
            arr.flags.writeable = False
    return replace(case, time=kept, displacement=disp, force=force, columns=columns,
                   test=replace(case.test, decimate=factor),
                   notes=(*case.notes, note))


def slosh_band_factor(case) -> int | None:
    """The factor that decimates ``case``'s record to about :data:`NOTE_RATE_HZ` when it is
    long and sampled far above the slosh band: at least :data:`NOTE_SAMPLES` samples, a
    factor of 2 or more that keeps the carriage motion (``[test] motion_band_hz``, else
    the measured displacement's :func:`~estimate.data.signals.motion_band`; a record
    without one, six-axis or crank-driven, is left alone) below :data:`FLAT` of the new
    rate and :data:`MIN_SAMPLES` samples; ``None`` otherwise, for a record that says
    ``[test] decimate`` and on the spinning rig (whose records are fitted as they come)."""
    if case.test.decimate is not None or case.test.rig != "lateral":
        return None
    n, rate = case.time.size, case.sample_rate
    factor = int(rate / NOTE_RATE_HZ * (1 + 1e-9))  # a 500 Hz record's rate is 499.99..
    if n < NOTE_SAMPLES or factor < 2:  # before reading the motion's band (every build asks)
        return None
    band = case.test.motion_band_hz
    if band is None and case.displacement is not None and not case.columns:
        from .signals import motion_band

        band = motion_band(case.time, case.displacement)
    elif band is None:  # a six-axis or crank record: its motion's band is not read here
        # (and decimating a six-axis record by 5 left its estimates but made its standard
        # errors 4 times wider: the residual there is the motion's own error in the band)
        return None
    if band:  # the carriage motion inside the flat band (nobody asked for this factor)
        factor = min(factor, int(FLAT * rate / band))
    return factor if factor >= 2 and n // factor >= MIN_SAMPLES else None


#: How many times the memory budget's samples a command that decimates by default reads
#: (``load_case(allowance=)``): a 1 kHz record decimated to :data:`NOTE_RATE_HZ`.
READ_ALLOWANCE = 10
#: What the note of a record decimated by default (:func:`slosh_band_decimated`) calls it.
DEFAULT_WHAT = ("by default, a long record sampled far above the slosh band; "
                "--decimate 1 or [test] decimate = 1 fits every sample")


def slosh_band_decimated(case):
    """``case`` decimated by :func:`slosh_band_factor` to about :data:`NOTE_RATE_HZ`, with
    a note saying it was the default and how to keep every sample; ``case`` itself when it
    is not long and sampled far above the slosh band (or says ``[test] decimate``).
    ``slosh fit`` and a campaign's fits do this: measured on sweeps from rest the
    estimates stay within 0.7 standard errors of the full rate's and their standard errors
    within 5 %, in a fifth of the time and memory; on records the model does not explain
    to the noise the intervals come out wider (the module's docstring)."""
    factor = slosh_band_factor(case)
    return case if factor is None else decimate_case(case, factor, DEFAULT_WHAT)


def decimation_note(case) -> str | None:
    """A note for a long record sampled far above the slosh band that is fitted at its full
    rate (no ``[test] decimate``): by how much to decimate it to about
    :data:`NOTE_RATE_HZ` (:func:`slosh_band_factor`); ``None`` otherwise."""
    factor = slosh_band_factor(case)
    if factor is None:
        return None
    n, rate = case.time.size, case.sample_rate
    return (f"{case.data_path.name}: {n} samples at {rate:.6g} Hz, far above the slosh band: "
            f"`[test] decimate = {factor}` (or --decimate {factor}) fits them at "
            f"{rate / factor:.6g} Hz in a fraction of the time and memory, with the same "
            "estimates where the model explains the record (estimate/data/decimation.py)")
