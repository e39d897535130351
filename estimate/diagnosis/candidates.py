"""Candidate extensions of an analog model, each a declared component or measurement
model, with its initial values from the evidence and a physical plausibility check."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from analogs import HingeDamper, HingeSpring, Model, Pendulum

from ..fitting.measurement import MeasurementModel, SensorDelay, StreamLag
from ..fitting.result import FitResult
from .evidence import Evidence

__all__ = ["Proposal", "propose", "CAUSES", "MODE_SCORE", "FREQUENCY_OFF"]

#: Score (chi-square reduction over the residual variance) a matched scan must reach for
#: another slosh mode to be fitted.
MODE_SCORE = 25.0
#: A first-mode frequency this far off the free-surface prediction (relative) makes the
#: diaphragm's hinge spring a candidate even when the case file mentions no diaphragm.
FREQUENCY_OFF = 0.03

#: The causes a diagnosis can name (documented in the README).
CAUSES = ("slosh_mode", "nonlinear_damping", "dry_friction", "nonlinear_stiffness",
          "diaphragm_stiffness", "sensor_delay", "sensor_offset", "rig_friction", "rotor",
          "rotary_oscillator", "hinge_torque")

#: Damping ratio of the rotary-oscillator probe of :func:`scan_rotary`: more than a slosh
#: resonance has, so that a trial frequency a grid step from a sharp resonance still
#: correlates with its response.
ROTARY_PROBE_DAMPING = 0.05
#: The rotary oscillator is proposed only when its scan explains this much more of the
#: residual than the rotor scan (an oscillator with a soft spring imitates a rotor).
ROTARY_MARGIN = 0.05


@dataclass(frozen=True)
class Proposal:
    """One candidate: the extended model and measurement models, initial values and bounds
    over the current estimates, what it adds, (for a sensor delay) the delay range to
    profile, and start values for a fit from the prediction when the current estimates are
    a poor start. ``plausible(result)`` returns ``None`` or the reason it is not physical."""

    cause: str
    added: tuple[str, ...]
    model: Model
    measurement: tuple[MeasurementModel, ...]
    initial: Mapping[str, float]
    bounds: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    hold: Mapping[str, float] = field(default_factory=dict)
    delay_range: tuple[float, float] | None = None
    #: start values of the new parameters read off the amplitude evidence, for a fit
    #: started from the tank prediction instead of the current estimates (``None``: none)
    cold_start: Mapping[str, float] | None = None
    #: other start values of the new parameters, over the current estimates, for a second
    #: fit when the first does not converge or leaves the residual far above the noise
    retry: Mapping[str, float] | None = None
    #: the objective reduction the candidate's screening predicts, over the residual
    #: variance (a score statistic; NaN: none, e.g. a spring with a held length)
    score: float = math.nan
    plausible: Callable[[FitResult], str | None] = field(default=lambda r: None, repr=False)
    describe: Callable[[FitResult], str] = field(default=lambda r: "", repr=False)


#: Smallest damping ratio of a slosh mode: viscous damping of liquid slosh is ~1e-3 in tanks
#: up to a metre (Mikishev's law) and higher for higher modes; a fitted "mode" that hardly
#: decays over a record (damping ratio ~0) is a constant tone in the force.
MIN_MODE_DAMPING = 2e-4


def _has(model: Model, cls, name: str) -> bool:
    return any(isinstance(c, cls) and c.name == name for c in model.components)


def _pendulums(model: Model) -> list[str]:
    return [c.name for c in model.components if isinstance(c, Pendulum)]


def _significant(res: FitResult, name: str, factor: float = 2.0) -> bool:
    return name in res.names and res.value(name) > factor * res.stderr[res.names.index(name)]


def _freq(res: FitResult, name: str) -> float:
    return res.derived.get(f"{name}.frequency_hz", (math.nan, 0))[0]


def _probe_regression(probe, J, r):
    """Regress the residual ``r`` on a unit probe response and the fit's sensitivity ``J``
    (one Gauss-Newton step of the extended model). Returns the probe's size (the residual is
    simulated - measured, so a missing element enters with minus its size) and the explained
    fraction of the residual."""
    import numpy as np

    A = np.column_stack([probe, J])
    coef, *_ = np.linalg.lstsq(A, r, rcond=None)
    explained = 1 - float(np.sum((r - A @ coef) ** 2) / np.sum(r**2))
    return -float(coef[0]), explained


def scan_mode(current: FitResult, f_lo: float, f_hi: float, *, n: int = 60, case: int = 0,
              zeta: float = 0.02) -> tuple[float, float, float] | None:
    """Matched scan for an unmodelled slosh mode: for trial frequencies in ``[f_lo, f_hi]``
    simulate a unit-mass pendulum driven by the case's carriage motion and regress the
    residual on its force together with the current fit's sensitivity columns (one
    Gauss-Newton step of the extended model, the other parameters readjusting). The probe
    is damped more (``zeta``) than a slosh mode, so that a trial frequency a grid step away
    from a sharp resonance still correlates with its response.
    Returns ``(frequency_hz, mass_kg, explained_fraction)`` of the best trial with a
    positive mass, or ``None`` (no carriage input, or nothing explained)."""
    import numpy as np

    from analogs import LateralRig
    from derive import derive, simulate

    exp = current.problem.experiments[case]
    dm0 = exp.derived
    if "rig.x_ddot" not in dm0.inputs:
        return None
    t = np.asarray(exp.case.time, float)
    w = current.weights[case] > 0
    r = current.residuals[case][w]
    g = exp.case.rig.gravity
    offset = sum(int(c.time.size) for c in (e.case for e in current.problem.experiments[:case]))
    J = current.sensitivity[offset:offset + t.size][w]
    probe = derive(LateralRig() + Pendulum("q") + HingeDamper("q"))
    excitation = exp.excitation
    if current.carriage and current.carriage[case] is not None:  # the estimated motion
        from derive import Sampled

        excitation = Sampled(t, current.carriage[case])

    def trial(f: float, z: float) -> tuple[float, float, float]:
        om = 2 * math.pi * f
        L = g / om**2
        sim = simulate(probe, {"rig.dry_mass": 0.0, "rig.gravity": g, "q.mass": 1.0, "q.length": L,
                               "q.damping": 2 * z * L**2 * om}, t, excitation,
                       outputs=("force_x",))
        return (float(f), *_probe_regression(sim.outputs[:, 0][w], J, r))

    best = None
    for f in np.geomspace(f_lo, f_hi, n):
        _, mass, explained = trial(f, zeta)
        if mass > 0 and (best is None or explained > best[2]):
            best = (float(f), mass, explained)
    if best is not None:
        # refine between the neighbouring grid points with a probe as lightly damped as a
        # slosh mode: a fit of a lightly damped mode started a grid step (2 %) off its
        # frequency can ring out of phase and diverge
        step = (f_hi / f_lo) ** (1 / max(n - 1, 1))
        fine = [trial(f, 0.5 * zeta) for f in np.geomspace(best[0] / step, best[0] * step, 9)]
        fine = [b for b in fine if b[1] > 0]
        if fine:
            best = max(fine, key=lambda b: b[2])
    return best


def scan_rotor(current: FitResult, *, case: int = 0, n: int = 16,
               rates: tuple[float, float] = (0.05, 20.0)) -> tuple[float, float, float] | None:
    """Matched scan for an unmodelled rotor on a rotating rig: for trial coupling rates
    ``c/J`` (1/s) in ``rates``, simulate a unit-inertia rotor about the tangential axis on
    the case's rig motion and regress the (scaled, all-channel) residual on its six outputs
    together with the current fit's sensitivity columns (one Gauss-Newton step of the
    extended model). Returns ``(inertia, damping, explained_fraction)`` of the best trial
    with a positive inertia, or ``None`` (the rig does not rotate, or nothing explained)."""
    import numpy as np

    from analogs import Rotor, SpinningRig

    from ..data.models import ROTOR_AXIS

    rig = current.problem.model.rig
    if not isinstance(rig, SpinningRig):
        return None
    grid = np.geomspace(*rates, n)
    best = _scan_spin_probe(current, case, Rotor("q", axis=ROTOR_AXIS),
                            [{"q.damping": float(rate)} for rate in grid])
    return None if best is None else (best[0], best[0] * float(grid[best[1]]), best[2])


def _scan_spin_probe(current: FitResult, case: int, component, trials: list[dict]
                     ) -> tuple[float, int, float] | None:
    """Simulate ``component`` (unit inertia ``q.inertia``) alone on the rig motion of
    ``case`` with each of ``trials``' parameter values and regress the fit's residual on
    its outputs (:func:`_probe_regression`). Returns ``(inertia, trial index,
    explained_fraction)`` of the best trial with a positive inertia, or ``None``."""
    import numpy as np

    from derive import RK4, derive, simulate

    problem = current.problem
    exp = problem.experiments[case]
    t = np.asarray(exp.case.time, float)
    r, J, chans, scales, w = _spin_residual(current, case)
    probe = derive(Model((problem.model.rig,)) + component)
    values = {k: v for k, v in problem.case_values(case, current.values).items()
              if k.startswith("rig.")}
    values["rig.dry_mass"] = 0.0
    best = None
    for k, trial in enumerate(trials):
        sim = simulate(probe, {**values, "q.inertia": 1.0, **trial}, t, exp.excitation,
                       integrator=RK4(), outputs=chans)
        y = (sim.outputs / scales[None, :]).ravel(order="F")[w]
        inertia, explained = _probe_regression(y, J, r)
        if inertia > 0 and (best is None or explained > best[2]):
            best = (inertia, k, explained)
    return best


def _spin_residual(current: FitResult, case: int):
    """The (scaled, channel-major) residual of ``case`` on its fitted samples, the fit's
    sensitivity rows for them, the channels and their scales."""
    import numpy as np

    chans = current.channels[case]
    scales = np.array([current.channel_scales[case][c] for c in chans])
    w = np.tile(current.weights[case] > 0, len(chans))
    r = (current.residuals[case] / scales).ravel(order="F")[w]
    offset = sum(int(np.size(current.residuals[k])) for k in range(case))
    J = current.sensitivity[offset:offset + r.size + int(np.count_nonzero(~w))][w]
    return r, J, chans, scales, w


def rotary_axes(rig) -> str:
    """The axes of a :class:`~analogs.RotaryOscillator` about the tank's radial and
    tangential directions: ``"xy"`` when the tank axis is the spin axis, ``"zy"`` when it
    points inward (:class:`~analogs.SpinningRig` ``tank_axis``)."""
    return "xy" if rig.tank_axis == "spin" else "zy"


def scan_rotary(current: FitResult, *, case: int = 0, n: int = 24,
                ratios: tuple[float, float] = (1.05, 6.0)) -> tuple[float, float, float] | None:
    """Matched scan for an unmodelled rotary oscillator (Green et al.) on a rotating rig:
    for trial natural frequencies ``omega_0`` (rad/s) from ``ratios`` times the spin rate
    (above it, where an oscillator damped relative to the tank is stable), simulate a
    unit-inertia oscillator with stiffness ``omega_0^2`` and damping ratio
    :data:`ROTARY_PROBE_DAMPING` on the case's rig motion, and regress the (scaled,
    all-channel) residual on its outputs together with the current fit's sensitivity
    columns. Its torques are proportional to its inertia at a given frequency and damping
    ratio. Returns ``(inertia, natural_frequency_rad_s, explained_fraction)`` of the best
    trial with a positive inertia, or ``None`` (the rig does not rotate, or nothing
    explained)."""
    import numpy as np

    from analogs import RotaryOscillator, SpinningRig

    problem = current.problem
    rig = problem.model.rig
    spin = problem.experiments[case].case.spin
    if not isinstance(rig, SpinningRig) or spin is None or not spin.rate:
        return None
    grid = abs(spin.rate) * np.geomspace(*ratios, n)
    best = _scan_spin_probe(current, case, RotaryOscillator("q", axes=rotary_axes(rig)),
                            [{"q.stiffness": float(w0**2),
                              "q.damping": 2 * ROTARY_PROBE_DAMPING * float(w0)} for w0 in grid])
    return None if best is None else (best[0], float(grid[best[1]]), best[2])


def _rotary_proposal(model: Model, measurement, current: FitResult, evidence: Evidence,
                     rotor_explained: float) -> Proposal | None:
    """A rotary oscillator when the residual is mostly torque and an oscillator above the
    spin rate explains clearly more of it than a rotor does (``rotor_explained``)."""
    from analogs import RotaryOscillator

    shares = evidence.channel_share
    torques = sum(v for k, v in shares.items() if k.startswith("torque"))
    if torques < 0.5:
        return None
    scan = scan_rotary(current)
    if scan is None or scan[2] < rotor_explained + ROTARY_MARGIN:
        return None
    inertia, w0, explained = scan
    spin = abs(current.problem.experiments[0].case.spin.rate)
    name = next(f"o{k}" for k in range(1, 99)
                if not any(c.name == f"o{k}" for c in model.components))
    axes = rotary_axes(model.rig)
    top = max(shares, key=shares.get)

    def plausible_rotary(r: FitResult) -> str | None:
        for k in (f"{name}.inertia", f"{name}.stiffness"):
            if not _significant(r, k, 3.0):
                return f"`{k}` = {r.value(k):.3g} is not distinguishable from zero"
        f = r.derived.get(f"{name}.frequency_hz", (math.nan, 0.0))[0]
        if not 2 * math.pi * f > spin:
            return (f"natural frequency {f:.3g} Hz is not above the spin rate "
                    f"({spin / (2 * math.pi):.3g} Hz): unstable with damping in the tank")
        return None

    def describe_rotary(r: FitResult) -> str:
        f = r.derived.get(f"{name}.frequency_hz", (math.nan, 0.0))[0]
        return (f"the residual is concentrated in the torques ({100 * torques:.0f} % of the "
                f"scaled residual power; largest share {top} {100 * shares.get(top, 0):.0f} %) "
                f"with little force, which the pendulum "
                f"cannot produce; {100 * explained:.0f} % of it is the torque of an oscillator "
                f"resonating near {w0 / (2 * math.pi):.3g} Hz (a rotor explains "
                f"{100 * rotor_explained:.0f} %) -> a rotary torque resonance of the liquid; "
                f"adding rotary oscillator {name} (inertia {r.value(f'{name}.inertia'):.3g} "
                f"kg m^2, natural frequency {f:.4g} Hz, damping ratio "
                f"{r.derived.get(f'{name}.damping_ratio', (math.nan, 0))[0]:.3g})")

    return Proposal(
        "rotary_oscillator", (name,), model + RotaryOscillator(name, axes=axes),
        tuple(measurement),
        {f"{name}.inertia": inertia, f"{name}.stiffness": inertia * w0**2,
         f"{name}.damping": 2 * ROTARY_PROBE_DAMPING * inertia * w0},
        plausible=plausible_rotary, describe=describe_rotary)


def _rotor_proposal(model: Model, measurement, current: FitResult,
                    evidence: Evidence, scan=None) -> Proposal | None:
    from analogs import Rotor, SpinningRig

    from ..data.models import ROTOR_AXIS

    if not isinstance(model.rig, SpinningRig):
        return None
    name = next(f"r{k}" for k in range(1, 99)
                if not any(c.name == f"r{k}" for c in model.components))
    if scan is None:
        return None
    inertia, damping, explained = scan
    shares = evidence.channel_share
    top = max(shares, key=shares.get) if shares else "torque_y"
    tangential = f"torque_{ROTOR_AXIS}"

    def plausible_rotor(r: FitResult) -> str | None:
        for k in (f"{name}.inertia", f"{name}.damping"):
            if not _significant(r, k, 3.0):
                return f"`{k}` = {r.value(k):.3g} is not distinguishable from zero"
        return None

    def describe_rotor(r: FitResult) -> str:
        torques = sum(v for k, v in shares.items() if k.startswith("torque"))
        return (f"the residual is concentrated in the torques ({100 * torques:.0f} % of the scaled "
                f"residual power; largest share {top} {100 * shares.get(top, 0):.0f} %, tangential "
                f"{tangential} {100 * shares.get(tangential, 0):.0f} %), which the pendulum, tied "
                f"to the forces, cannot produce; {100 * explained:.0f} % of the residual is the "
                f"torque of a rotor about the tangential axis driven by the nutation -> rotational "
                f"slosh; adding rotor {name} (inertia {r.value(f'{name}.inertia'):.3g} kg m^2, "
                f"damping {r.value(f'{name}.damping'):.3g} N m s/rad)")

    return Proposal(
        "rotor", (name,), model + Rotor(name, axis=ROTOR_AXIS), tuple(measurement),
        {f"{name}.inertia": inertia, f"{name}.damping": damping},
        plausible=plausible_rotor, describe=describe_rotor)


def propose(model: Model, measurement: tuple[MeasurementModel, ...], current: FitResult,
            evidence: Evidence, *, gravity: float, predicted: Mapping[str, float]
            ) -> list[Proposal]:
    """The candidate extensions of ``model`` that the score screening cannot rank (they add
    states, change a held parameter or shift the data): another slosh mode (matched scan),
    a diaphragm's hinge spring with the length held near the prediction, a sensor delay
    (profiled; unless the fits estimate a stream lag) and, on a rotating rig, a rotor. A
    matched scan's score is the proposal's :attr:`Proposal.score`."""
    values = dict(zip(current.names, current.values))
    out: list[Proposal] = []
    if len(current.channels[0] if current.channels else ()) > 1:
        # multi-channel (spinning rig): the lateral candidates read the carriage input and
        # the lateral force; here only what the rig's rotation can reveal
        scan = scan_rotor(current)
        rotor = _rotor_proposal(model, measurement, current, evidence, scan)
        rotary = _rotary_proposal(model, measurement, current, evidence,
                                  scan[2] if scan is not None else 0.0)
        return [p for p in (rotor, rotary) if p is not None]
    pend = _pendulums(model)
    p1 = pend[0] if pend else None
    m1 = values.get(f"{p1}.mass", 1.0) if p1 else 1.0
    f1 = _freq(current, p1) if p1 else math.nan

    # -- an additional slosh mode -------------------------------------------------------------
    name = f"p{len(pend) + 1}"
    peaks = [p for p in evidence.unexplained_peaks() if not (f1 and abs(p.frequency / f1 - 1) < 0.1)]
    coherent = [p for p in peaks if p.coherence >= 0.3] or peaks
    f_top = pend[-1] and _freq(current, pend[-1]) if pend else math.nan
    cutoff = current.problem.force_cutoff_hz or 20.0
    scan = (scan_mode(current, 1.15 * f_top, min(0.9 * cutoff, 4.0 * f_top))
            if math.isfinite(f_top) else None)
    f0 = m0 = None
    statistic = _scan_statistic(current, scan[2]) if scan is not None else 0.0
    if scan is not None and statistic >= MODE_SCORE:
        f0, m0, explained = scan
        near = [p for p in coherent if abs(p.frequency / f0 - 1) < 0.1]
        peak_text = (f"{100 * explained:.0f} % of the residual (score {statistic:.0f}) is the "
                     f"response of an oscillator at {f0:.3g} Hz driven by the carriage"
                     + (f", with a residual peak at {near[0].frequency:.3g} Hz (coherence "
                        f"{near[0].coherence:.2f}) that is not a drive harmonic" if near else ""))
    if f0 is not None:
        L0 = gravity / (2 * math.pi * f0) ** 2
        m0 = m0 if m0 is not None else predicted.get(f"{name}.mass", 0.04 * m1)

        def damping(m: float, L0=L0, f0=f0) -> float:  # 1 % of critical at f0
            return 2 * 0.01 * m * L0**2 * 2 * math.pi * f0

        c0 = damping(m0)

        def plausible_mode(r: FitResult, name=name, prev=pend[-1] if pend else None) -> str | None:
            m, f = r.value(f"{name}.mass"), _freq(r, name)
            if prev and not f > 1.15 * _freq(r, prev):
                return f"{name} at {f:.3g} Hz is not above the mode it would follow"
            if prev and not m < r.value(f"{prev}.mass"):
                return f"{name} mass {m:.3g} kg is not below the lower mode's"
            if not _significant(r, f"{name}.mass", 3.0):
                return f"{name} mass {m:.3g} kg is not distinguishable from zero"
            zeta = r.derived.get(f"{name}.damping_ratio", (math.nan, 0.0))[0]
            if zeta < MIN_MODE_DAMPING:
                return (f"{name} damping ratio {zeta:.2g}: an oscillation at {f:.3g} Hz that does "
                        f"not decay over the record is a tone or a structural ringing, not slosh")
            return None

        # the scan's linear probe reads the mass off the response amplitude, which a mode
        # swinging far into its nonlinear range (tenths of a radian in a sweep through it)
        # does not have: when that start fails, the tank's prediction of the mode's mass at
        # the scanned frequency is the second (F60_sweep_0.6mm: the scan read 0.008 kg of
        # 0.048 and its fit ran out of iterations)
        retry = None
        if f"{name}.mass" in predicted:
            mp = predicted[f"{name}.mass"]
            retry = {f"{name}.mass": mp, f"{name}.length": L0,
                     f"{name}.damping": damping(mp)}
        out.append(Proposal(
            "slosh_mode", (name,), model + Pendulum(name) + HingeDamper(name), measurement,
            {f"{name}.mass": m0, f"{name}.length": L0, f"{name}.damping": c0},
            score=statistic, retry=retry,
            bounds={f"{name}.length": (0.8 * L0, 1.25 * L0),
                    f"{name}.mass": (1e-6, min(m1, max(5 * predicted.get(f"{name}.mass", 0.0), 0.1 * m1)))},
            plausible=plausible_mode,
            describe=lambda r, name=name, txt=peak_text: (
                f"{txt} -> an unmodelled slosh mode; adding pendulum {name} "
                f"({r.value(f'{name}.mass'):.3g} kg, {_freq(r, name):.3g} Hz)")))

    if p1 is None:
        return out

    # -- diaphragm stiffness: hinge spring, length held near the prediction ----------------------
    # only when the case says there is a diaphragm or the frequency is off the prediction
    ratio = evidence.frequency_ratio
    off = ratio is not None and abs(ratio - 1) > FREQUENCY_OFF
    diaphragm = current.problem.experiments[0].case.tank.diaphragm
    if not _has(model, HingeSpring, p1) and f"{p1}.length" in predicted and (off or diaphragm):
        Lp = predicted[f"{p1}.length"]
        m = values.get(f"{p1}.mass", m1)
        w2 = (2 * math.pi * f1) ** 2 if math.isfinite(f1) else gravity / Lp
        k0 = max(m * Lp**2 * w2 - m * gravity * Lp, 0.05 * m * gravity * Lp)

        def plausible_spring(r: FitResult) -> str | None:
            if not _significant(r, f"{p1}.stiffness", 3.0):
                return "the hinge stiffness is not distinguishable from zero"
            return None

        def describe_spring(r: FitResult) -> str:
            k, m_, L_ = r.value(f"{p1}.stiffness"), r.value(f"{p1}.mass"), r.value(f"{p1}.length")
            raise_ = math.sqrt(1 + k / (m_ * gravity * L_)) - 1
            pinned = f"; `{p1}.length` was pinned at its bound" if f"{p1}.length" in evidence.pinned else ""
            return (f"the fitted frequency is {100 * (ratio - 1):+.1f} % off the free-surface prediction"
                    f"{pinned} -> a restoring stiffness the liquid alone lacks (diaphragm); a hinge "
                    f"spring on {p1} with the length held near the prediction "
                    f"(k = {k:.3g} N m/rad, +{100 * raise_:.1f} % frequency, damping ratio "
                    f"{r.derived.get(f'{p1}.damping_ratio', (math.nan, 0))[0]:.3g})") if ratio else (
                    f"a hinge spring on {p1} (k = {k:.3g} N m/rad)")

        out.append(Proposal(
            "diaphragm_stiffness", (f"{p1}:spring",), model + HingeSpring(p1), measurement,
            {f"{p1}.stiffness": k0, f"{p1}.length": Lp},
            bounds={f"{p1}.length": (0.99 * Lp, 1.01 * Lp)},
            plausible=plausible_spring, describe=describe_spring))

    # -- sensor delay (measurement model, delay profiled) -----------------------------------------
    # always a candidate where the fits do not estimate a stream lag themselves: its
    # linearised profile (the search's score) decides whether it is fitted, not a dF/dt
    # correlation, which a 20 ms lag on a transport record left at 0.1 ms
    if not any(isinstance(mm, (SensorDelay, StreamLag)) for mm in measurement):
        def describe_delay(r: FitResult) -> str:
            tau = next(mm.delay for mm in r.problem.measurement if isinstance(mm, SensorDelay))
            return (f"the objective's profile over a delay of the recorded force is lowest "
                    f"away from zero (residual correlation with dF/dt "
                    f"{evidence.skew_correlation:+.2f}) -> a timing skew; a sensor delay of "
                    f"{1e3 * tau:.1f} ms on the measured force")

        def plausible_delay(r: FitResult) -> str | None:
            tau = next(mm.delay for mm in r.problem.measurement if isinstance(mm, SensorDelay))
            if not 1e-3 <= tau <= 0.095:
                return f"the delay {1e3 * tau:.1f} ms is at the edge of the searched range"
            return None

        out.append(Proposal("sensor_delay", ("sensor_delay",), model, measurement, {},
                            delay_range=(0.0, 0.1), plausible=plausible_delay,
                            describe=describe_delay))

    return out


def _scan_statistic(current: FitResult, explained: float, case: int = 0) -> float:
    """The chi-square reduction a matched scan's explained fraction of the fitted residual
    stands for, over the residual variance (the score of the scanned candidate)."""
    import numpy as np

    w = current.weights[case] > 0 if current.weights else slice(None)
    scale = current.problem.channel_scales(case)["force_x"]
    r = np.asarray(current.residuals[case])[w] / scale
    return float(explained * (r @ r) / max(current.residual_variance, 1e-300))
