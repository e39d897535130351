"""The carriage motion as part of the estimate (errors in variables).

A measured displacement is noisy, and differentiating it twice to drive the model turns
that noise, and every filter's error during the start-up ramp, into force the fit must
explain: it moves the mass split and reports intervals that treat the input as exact. Here
the carriage displacement is instead a quintic B-spline whose coefficients are decision
variables of the same NLP as the parameters. Two residuals tie it to the record: the
measured displacement (weighted by the displacement noise) and the measured force
(weighted by the force noise), so the acceleration that drives the model is the one both
measurements support together.

The knots are uniform, spaced ``1 / (12 f_top)`` with ``f_top`` the highest significant
frequency of the carriage motion (:func:`estimate.data.signals.motion_band`, or the case's
``[test] motion_band_hz``; at least one sample, at most :data:`MAX_SPACING` - also the
spacing of a carriage at rest, whose displacement holds nothing above its noise): a quintic
spline then represents the carriage acceleration to ~2e-4 of its amplitude. The noise band
starts above the carriage motion's frequencies, or, when the carriage stands still, above
the force's own (a free decay's force rings at the slosh frequency). The force residuals
are weighed by the force's noise figure (:mod:`estimate.data.signals.noise_figure`): read
from the record's quiet segments (the rest before the drive, a settled end) when it has
them, else provisionally from the white level above the signal band, and then from the
fit's residual (:mod:`estimate.fitting.noise_figures`). The displacement noise is its white
level above the signal band (:func:`estimate.data.signals.noise_level`), or its quiet
segments' level when that is larger (a low-passed displacement sensor), or the start
spline's misfit when that is clearly larger still: noise that is not white, as a
displacement integrated from an accelerometer has, :data:`COLOURED_FACTOR`. A record that
starts quiet starts with the carriage at rest (zero velocity and acceleration at the first
sample).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sps
import scipy.sparse.linalg  # noqa: F401  (sps.linalg)
from scipy.interpolate import BSpline

from derive import Excitation

from ..data.signals import (
    motion_band,
    noise_level,
    remove_tones,
    significant_frequencies,
    starts_quiet,
)
from ..data.signals.noise_figure import NoiseFigure, quiet_segments, segment_noise

__all__ = ["CarriageSpline", "CarriageInput", "SplineExcitation", "RecordNoise",
           "carriage_input", "noise_band", "record_noise"]

#: Knots per period of the highest significant carriage frequency.
KNOTS_PER_PERIOD = 6
#: Largest knot spacing [s], also of the knots where the carriage rests (before and after a
#: transport move): there the spline has nothing to follow but would absorb force noise.
MAX_SPACING = 0.25
#: The carriage rests while its displacement stays within this many noise standard
#: deviations of its first (last) value; the knots are dense from MOTION_MARGIN s before it
#: leaves rest to MOTION_MARGIN s after it comes back (the force sees a smooth start first).
REST_SIGMAS = 6.0
MOTION_MARGIN = 0.3
#: The noise band starts this factor above the highest significant carriage frequency, and
#: never below NOISE_BAND_MIN_HZ (the slosh modes and their harmonics live below).
NOISE_BAND_FACTOR = 3.0
NOISE_BAND_MIN_HZ = 12.0
#: Noise levels are floored at this fraction of the signal's RMS: a noiseless synthetic
#: record must not get an infinite weight.
NOISE_FLOOR = 1e-6
#: The displacement noise is taken from the start spline's misfit when that exceeds the
#: white level above the band by this factor (white noise: the two agree within a few per
#: cent; a displacement integrated from an accelerometer: its red noise between the
#: spline's resolution and the band, 10-100 times the level above the band).
COLOURED_FACTOR = 1.5


@dataclass(frozen=True)
class CarriageSpline:
    """A uniform B-spline of ``degree`` on ``knots`` (s); the spline is valid (full support)
    on ``[knots[degree], knots[-degree - 1]]``, which covers the record."""

    knots: np.ndarray = field(repr=False)
    degree: int = 5

    @classmethod
    def covering(cls, t0: float, t1: float, spacing: float, degree: int = 5) -> "CarriageSpline":
        """Uniform knots at most ``spacing`` apart whose spline is valid exactly on
        ``[t0, t1]`` (a knot on each end, so no basis function barely touches the record)."""
        m = max(int(np.ceil((t1 - t0) / spacing - 1e-9)), 1)
        knots = t0 + (t1 - t0) * np.arange(-degree, m + degree + 1) / m
        knots[degree], knots[m + degree] = t0, t1  # exact ends: no round-off outside
        return cls(knots, degree)

    @classmethod
    def graded(cls, t0: float, t1: float, spacing: float, moving: tuple[float, float],
               rest_spacing: float, degree: int = 5) -> "CarriageSpline":
        """Knots ``spacing`` apart while the carriage moves (``moving``, s) and at most
        ``rest_spacing`` apart where it rests, the spacing growing by at most half from one
        knot to the next; a knot on each end of ``[t0, t1]``."""
        a, b = max(moving[0], t0), min(moving[1], t1)
        if b - a >= t1 - t0 - 2 * spacing or rest_spacing <= spacing:
            return cls.covering(t0, t1, spacing, degree)
        inner = a + (b - a) * np.arange(max(int(np.ceil((b - a) / spacing)), 1) + 1) \
            / max(int(np.ceil((b - a) / spacing)), 1)
        right = _grown(b, t1, spacing, rest_spacing)
        left = a - (_grown(0.0, a - t0, spacing, rest_spacing))[::-1]
        inside = np.unique(np.r_[t0, left, inner, right, t1])
        inside = inside[(inside >= t0) & (inside <= t1)]
        keep = np.r_[True, np.diff(inside) > 0.5 * spacing]  # no knots closer than that
        inside = inside[keep]
        inside[-1] = t1
        h0, h1 = inside[1] - inside[0], inside[-1] - inside[-2]
        knots = np.r_[t0 - h0 * np.arange(degree, 0, -1), inside,
                      t1 + h1 * np.arange(1, degree + 1)]
        return cls(knots, degree)

    @property
    def spacing(self) -> float:
        """The smallest knot spacing (s)."""
        return float(np.min(np.diff(self.knots)))

    @property
    def n_coefficients(self) -> int:
        return self.knots.size - self.degree - 1

    def design(self, times: np.ndarray, derivative: int = 0) -> sps.csr_matrix:
        """``(len(times), n_coefficients)`` matrix mapping coefficients to the spline's
        ``derivative``-th time derivative at ``times`` (m, m/s, m/s^2)."""
        k, d, tau = self.degree, derivative, self.knots
        basis = BSpline.design_matrix(np.asarray(times, float), tau[d:tau.size - d], k - d)
        D = sps.identity(self.n_coefficients, format="csr")
        for j in range(d):
            m = self.n_coefficients - j
            # the derivative of a B-spline of degree q on knots tau is one of degree q - 1 on
            # tau[1:-1] with coefficients q (c[i+1] - c[i]) / (tau[i+q+1] - tau[i+1])
            q, knots = k - j, tau[j:tau.size - j]
            scale = q / (knots[q + 1:q + m] - knots[1:m])
            Dj = sps.diags([-scale, scale], [0, 1], shape=(m - 1, m))
            D = Dj @ D
        return (basis @ D).tocsr()

    def inputs_matrix(self, times: np.ndarray) -> sps.csr_matrix:
        """Matrix mapping coefficients to ``[x, xd, xdd]`` at every time, time by time
        (rows ``3 i``, ``3 i + 1``, ``3 i + 2``), the order of a column-major ``(3, n)``."""
        blocks = [self.design(times, d) for d in range(3)]
        n = len(times)
        order = np.arange(3 * n).reshape(3, n).T.ravel()  # interleave x, xd, xdd per time
        return sps.vstack(blocks, format="csr")[order]



def _grown(start: float, stop: float, spacing: float, largest: float) -> np.ndarray:
    """Knots from ``start`` towards ``stop`` (excluded unless reached), the spacing growing
    from ``spacing`` by half a step at a time up to ``largest``; the last interval stretched
    or merged so that ``stop`` is a knot."""
    out, h, x = [], spacing, start
    while x + h < stop - 1e-12:
        h = min(1.5 * h, largest)
        x += h
        out.append(x)
    if out and stop - out[-1] < 0.5 * h:
        out.pop()
    return np.array(out + [stop])


@dataclass(frozen=True)
class CarriageInput:
    """What the NLP needs to estimate one case's carriage motion.

    The estimated coefficients are those of ``spline`` mapped by ``basis`` (``None``: the
    identity); a record that starts at rest uses a basis whose splines all have zero
    velocity and acceleration at the first sample, so rest needs no constraint.

    Attributes
    ----------
    spline : CarriageSpline
        The representation of the displacement.
    basis : scipy.sparse matrix or None
        ``(spline.n_coefficients, n_coefficients)``: spline coefficients from estimated ones.
    coefficients : numpy.ndarray
        Start values (m): the least-squares spline through the measured displacement.
    displacement_noise : float
        Standard deviation of the noise on the recorded displacement (m): its white level
        above the signal band, or its quiet segments' level when larger.
    displacement : numpy.ndarray
        The recorded displacement without tones above the signal band (m), as fitted.
    displacement_tones : tuple of (float, float)
        The tones removed: frequency (Hz) and amplitude (m).
    at_rest : bool
        The record starts quiet: the carriage velocity and acceleration are 0 at ``t[0]``.
    coloured_noise : bool
        The displacement's noise is not white: the least-squares spline misses the record
        by more than :data:`COLOURED_FACTOR` times the white level above the band (a
        displacement integrated from an accelerometer: its noise grows towards low
        frequencies), so ``displacement_noise`` is that misfit's standard deviation
        (``n - coefficients`` degrees of freedom).
    """

    spline: CarriageSpline
    basis: sps.spmatrix | None = field(repr=False)
    coefficients: np.ndarray = field(repr=False)
    displacement_noise: float
    displacement: np.ndarray = field(repr=False)
    displacement_tones: tuple[tuple[float, float], ...]
    at_rest: bool
    coloured_noise: bool = False
    _memo: dict = field(default_factory=dict, compare=False, repr=False)
    _shift_memo: dict = field(default_factory=dict, compare=False, repr=False)

    def derivative_designs(self, times: np.ndarray, order: int) -> tuple:
        """``design(times, d) / d!`` for ``d = 0..order`` as sparse CasADi matrices: the
        Taylor series of the spline shifted in time (a stream lag). Kept with this object."""
        import math

        from ._sparse import sparse_dm

        t = np.asarray(times, float)
        key = (t.tobytes(), order)
        if key not in self._shift_memo:
            self._shift_memo.clear()
            self._shift_memo[key] = tuple(sparse_dm(self.design(t, d) / math.factorial(d))
                                          for d in range(order + 1))
        return self._shift_memo[key]

    @property
    def n_coefficients(self) -> int:
        return self.spline.n_coefficients if self.basis is None else self.basis.shape[1]

    def design(self, times: np.ndarray, derivative: int = 0) -> sps.csr_matrix:
        """Estimated coefficients to the ``derivative``-th derivative at ``times``."""
        B = self.spline.design(times, derivative)
        return B if self.basis is None else (B @ self.basis).tocsr()

    def inputs_matrix(self, times: np.ndarray) -> sps.csr_matrix:
        """Estimated coefficients to ``[x, xd, xdd]`` time by time (see
        :meth:`CarriageSpline.inputs_matrix`)."""
        A = self.spline.inputs_matrix(times)
        return A if self.basis is None else (A @ self.basis).tocsr()

    def casadi_matrices(self, times: np.ndarray, fractions: np.ndarray):
        """``(A_stage, A_grid, B0)`` as sparse CasADi matrices: :meth:`inputs_matrix` at
        the stage times ``times[k] + fractions * (times[k+1] - times[k])`` and at ``times``,
        and :meth:`design` at ``times``. Kept with this object: every fit of the record
        (the diagnosis fits many models to it) reuses them."""
        t = np.asarray(times, float)
        fr = np.asarray(fractions, float)
        key = (t.tobytes(), fr.tobytes())
        if key not in self._memo:
            from ._sparse import sparse_dm

            stage_times = (t[:-1, None] + np.diff(t)[:, None] * fr[None, :]).ravel()
            self._memo.clear()  # one grid at a time: these are large
            A_stage = sparse_dm(self.inputs_matrix(stage_times))
            if fr[0] == 0.0 and fr[-1] == 1.0:
                # the grid times are stage times (each interval's first, and the last
                # interval's end): rows of A_stage, sliced in CasADi (no second conversion)
                m, n = fr.size, t.size
                k, i = np.arange(n)[:, None], np.arange(3)[None, :]
                rows = np.where(k < n - 1, 3 * m * k + i, 3 * m * (n - 2) + 3 * (m - 1) + i)
                A_grid = A_stage[rows.ravel().tolist(), :]
                B0 = A_stage[rows[:, 0].tolist(), :]
            else:
                A_grid, B0 = sparse_dm(self.inputs_matrix(t)), sparse_dm(self.design(t))
            self._memo[key] = (A_stage, A_grid, B0)
        return self._memo[key]

    def values(self, coefficients: np.ndarray, times: np.ndarray) -> np.ndarray:
        """``(3, len(times))``: displacement (m), velocity (m/s), acceleration (m/s^2)."""
        c = np.asarray(coefficients, float)
        spline = BSpline(self.spline.knots, c if self.basis is None else self.basis @ c,
                         self.spline.degree)
        t = np.asarray(times, float)
        return np.vstack([spline(t, nu=d) for d in range(3)])

    def excitation(self, coefficients: np.ndarray) -> "SplineExcitation":
        """The carriage motion of ``coefficients`` as a rig excitation."""
        return SplineExcitation(self, np.asarray(coefficients, float))


@dataclass(frozen=True)
class SplineExcitation(Excitation):
    """An estimated carriage motion (:class:`CarriageInput` and its coefficients) as the
    rig excitation: the spline's exact displacement (m), velocity (m/s) and acceleration
    (m/s^2) at any time of the record."""

    carriage: CarriageInput = field(repr=False)
    coefficients: np.ndarray = field(repr=False)

    def values(self, t: np.ndarray) -> np.ndarray:
        return self.carriage.values(self.coefficients, t)


def _rest_basis(spline: CarriageSpline, t0: float) -> sps.csr_matrix:
    """Basis of the splines with zero velocity and acceleration at ``t0``: the first two
    coefficients follow from the others, ``c01 = -C01^-1 C_rest c_rest``."""
    C = sps.vstack([spline.design([t0], 1), spline.design([t0], 2)]).toarray()
    n = spline.n_coefficients
    head = -np.linalg.solve(C[:, :2], C[:, 2:])
    return sps.vstack([sps.csr_matrix(head), sps.identity(n - 2, format="csr")]).tocsr()


@dataclass(frozen=True)
class RecordNoise:
    """The force of a record as the estimated-input fit uses it.

    Attributes
    ----------
    force_noise : float
        The force noise (N) the force residuals are divided by: ``figure.std``.
    force : numpy.ndarray
        The recorded force without the tones above ``band_hz`` (N).
    tones : tuple of (float, float)
        The tones removed: frequency (Hz) and amplitude (N).
    band_hz : float
        Lower edge of the band above the mechanics (Hz) where tones were read.
    figure : NoiseFigure
        The force's noise figure as known before the fit: from quiet segments
        (``source == "quiet"``), else the white level above ``band_hz`` (``"spectrum"``,
        provisional: the fit reads the figure from its residual,
        :mod:`estimate.fitting.noise_figures`), or a residual's figure when a fit was
        re-weighed by it (``"residual"``).
    quiet : tuple of (int, int)
        Index ranges of the record's quiet segments.
    """

    force_noise: float
    force: np.ndarray = field(repr=False)
    tones: tuple[tuple[float, float], ...]
    band_hz: float
    figure: NoiseFigure | None = None
    quiet: tuple[tuple[int, int], ...] = ()

    def weighed_by(self, figure: NoiseFigure) -> "RecordNoise":
        """A copy whose force residuals are divided by ``figure``."""
        return replace(self, force_noise=float(figure.std), figure=figure)


def noise_band(top_frequency: float) -> float:
    """Lower edge [Hz] of the band above mechanics reaching up to ``top_frequency`` [Hz]."""
    return max(NOISE_BAND_FACTOR * top_frequency, NOISE_BAND_MIN_HZ)


def record_noise(time: np.ndarray, force: np.ndarray, top_frequency: float, *,
                 quiet: tuple[tuple[int, int], ...] = ()) -> RecordNoise:
    """Noise figure and tones of a recorded force (N) whose mechanics reach up to
    ``top_frequency`` (Hz): tones read above ``max(3 top_frequency, 12 Hz)``; the figure from
    the ``quiet`` segments (index ranges) when there are any, else provisionally the white
    level above that band."""
    band = noise_band(top_frequency)
    F = np.asarray(force, float)
    clean, tones = remove_tones(time, F, above_hz=band)
    floor = NOISE_FLOOR * float(np.sqrt(np.mean(F**2)))
    if quiet:
        figure = segment_noise(time, clean, quiet, detail=_quiet_text(time, quiet))
    else:
        figure = NoiseFigure(noise_level(time, clean, above_hz=band), "spectrum", (),
                             float(time[-1] - time[0]),
                             f"white level above {band:.3g} Hz, provisional")
    if figure.std < floor:
        figure = replace(figure, std=floor)
    return RecordNoise(figure.std, clean, tones, band, figure, tuple(quiet))


def _quiet_text(time: np.ndarray, quiet: tuple[tuple[int, int], ...]) -> str:
    names = []
    for a, b in quiet:
        what = "rest before the drive" if a == 0 else "settled end"
        names.append(f"{what} {time[a]:.3g}-{time[b - 1]:.3g} s")
    return "quiet segments: " + ", ".join(names)


def carriage_input(time: np.ndarray, displacement: np.ndarray, *,
                   at_rest: bool | None = None,
                   force: np.ndarray | None = None,
                   motion_band_hz: float | None = None) -> tuple[CarriageInput, RecordNoise]:
    """Spline, start values and noise levels for estimating the carriage motion of a record
    (``time`` s, ``displacement`` m, ``force`` N), and the force's noise. ``at_rest=None``
    detects a quiet start (:func:`estimate.data.signals.starts_quiet` on both channels);
    ``motion_band_hz`` (Hz) is the carriage motion's highest frequency, which sets the knot
    spacing (default: :func:`estimate.data.signals.motion_band` of the displacement).

    The last few records' results are kept (keyed by the samples' bytes): the diagnosis
    builds a problem per candidate model of the same record. The returned objects are
    shared; treat them as read-only."""
    arrays = [None if a is None else np.ascontiguousarray(a, float)
              for a in (time, displacement, force)]
    key = (hashlib.sha256(b"".join(b"" if a is None else a.tobytes() for a in arrays)).hexdigest(),
           tuple(-1 if a is None else a.size for a in arrays), at_rest, motion_band_hz)
    if key not in _RECENT:
        _RECENT[key] = _carriage_input(arrays[0], arrays[1], arrays[2], at_rest=at_rest,
                                       motion_band_hz=motion_band_hz)
        while len(_RECENT) > _RECENT_SIZE:
            _RECENT.pop(next(iter(_RECENT)))
    return _RECENT[key]


_RECENT: dict = {}
_RECENT_SIZE = 4


def adopt_noise(old: RecordNoise, new: RecordNoise) -> None:
    """Keep ``new`` in place of ``old`` among the kept :func:`carriage_input` results: later
    problems built on the same record are weighed by ``new`` at once (a figure read from a
    fit's residual, :func:`estimate.fitting.noise_figures.reweighed`)."""
    for key, (ci, rn) in list(_RECENT.items()):
        if rn is old:
            _RECENT[key] = (ci, new)


def forget_records() -> None:
    """Drop the kept :func:`carriage_input` results (benchmarks time a first fit of a
    record with it)."""
    _RECENT.clear()


def _carriage_input(time: np.ndarray, displacement: np.ndarray, force: np.ndarray, *,
                    at_rest: bool | None, motion_band_hz: float | None = None
                    ) -> tuple[CarriageInput, RecordNoise]:
    t = np.asarray(time, float)
    x = np.asarray(displacement, float)
    dt = float(np.median(np.diff(t)))
    f_motion = motion_band_hz or motion_band(t, x)
    spacing = MAX_SPACING if f_motion is None else \
        min(max(1.0 / (KNOTS_PER_PERIOD * f_motion), dt), MAX_SPACING)
    if f_motion is None:  # a carriage at rest: the force's own mechanics (a free decay's)
        f_top = max(significant_frequencies(t, np.asarray(force, float), derivative=0),
                    default=0.0)
    else:
        f_top = f_motion
    band = noise_band(f_top)
    x_clean, x_tones = remove_tones(t, x, above_hz=band)
    sx = max(noise_level(t, x_clean, above_hz=band), NOISE_FLOOR * float(np.std(x)))
    F_clean, _ = remove_tones(t, np.asarray(force, float), above_hz=band)
    quiet = quiet_segments(t, x_clean, F_clean, displacement_noise=sx, band_hz=band,
                           starts_at_rest=at_rest)
    noise = record_noise(t, force, f_top, quiet=quiet)
    if quiet:
        sx = max(sx, segment_noise(t, x_clean, quiet).std)
    if at_rest is None:
        at_rest = starts_quiet(t, x_clean, sx) and starts_quiet(t, noise.force, noise.force_noise)
    spline = CarriageSpline.graded(float(t[0]), float(t[-1]), spacing,
                                   _moving(t, x_clean, REST_SIGMAS * sx,
                                           1.0 / f_top if f_top > 0 else MAX_SPACING),
                                   MAX_SPACING)
    basis = _rest_basis(spline, float(t[0])) if at_rest else None
    B = spline.design(t) if basis is None else (spline.design(t) @ basis).tocsr()
    coefficients = _least_squares(B, x_clean)
    s_fit = _misfit(B, coefficients, x_clean)
    coloured = s_fit > COLOURED_FACTOR * sx
    if coloured:
        # a drifting displacement leaks into the tone fit (offset and trend only): look
        # for tones in what the spline does not follow, then fit the spline again
        smooth = B @ _least_squares(B, x)
        rest, x_tones = remove_tones(t, x - smooth, above_hz=noise.band_hz)
        x_clean = smooth + rest
        coefficients = _least_squares(B, x_clean)
        s_fit = _misfit(B, coefficients, x_clean)
        coloured = s_fit > COLOURED_FACTOR * sx
    ci = CarriageInput(spline, basis, coefficients, s_fit if coloured else sx, x_clean, x_tones,
                       bool(at_rest), coloured_noise=coloured)
    return ci, noise


def _misfit(B: sps.spmatrix, coefficients: np.ndarray, x: np.ndarray) -> float:
    """Standard deviation of what the spline (design ``B``) misses of ``x`` (its degrees of
    freedom: samples less coefficients)."""
    r = x - B @ coefficients
    return float(np.sqrt(r @ r / max(x.size - B.shape[1], 1)))


def _moving(t: np.ndarray, x: np.ndarray, tolerance: float, period: float
            ) -> tuple[float, float]:
    """The span (s) in which the carriage moves: from a margin before the displacement ``x``
    (m) first leaves ``tolerance`` of its first value to a margin after it last leaves
    that of its final one; the margin is :data:`MOTION_MARGIN` s, at least ``period``."""
    away = np.flatnonzero(np.abs(x - np.median(x[:10])) > tolerance)
    back = np.flatnonzero(np.abs(x - np.median(x[-10:])) > tolerance)
    if away.size == 0 or back.size == 0:
        return float(t[0]), float(t[-1])
    margin = max(MOTION_MARGIN, period)
    return float(t[away[0]] - margin), float(t[back[-1]] + margin)


def _least_squares(B: sps.spmatrix, x: np.ndarray) -> np.ndarray:
    """Coefficients of the spline (design ``B``) through the samples ``x``."""
    A = (B.T @ B).tocsc()
    # a ridge far below the data's weight keeps every coefficient defined
    A = A + 1e-10 * A.diagonal().mean() * sps.identity(A.shape[0], format="csc")
    return np.asarray(sps.linalg.spsolve(A, B.T @ x)).ravel()
