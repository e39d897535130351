"""Signal processing for tank-test records: zero-phase filtering, spectra, derivatives.

All functions take uniformly sampled ``time`` [s] and a signal of the same length, and never
modify their inputs.

* :func:`lowpass` - zero-phase Butterworth low-pass (default 10 Hz, as the classical workflow),
  ``scipy.signal.butter(..., output="sos")`` + ``sosfiltfilt``.
* :func:`welch_spectrum`, :func:`find_spectral_peaks`, :func:`dominant_frequency` - Welch power
  spectrum and its peaks; each peak frequency is refined by a least-squares sinusoid fit to the
  whole record (a "zoom" around the Welch bin), which resolves a drive frequency to far better
  than 0.1% on a 20-30 s record.
* :func:`check_drive_frequency` - the classical data check: the dominant force frequency must match
  the drive frequency within 1.5%.
* :class:`NoiseFigure`, :func:`quiet_segments`, :func:`segment_noise`,
  :func:`residual_noise` - the noise of a channel inside the signal band, from quiet segments
  or a fit's residual (:mod:`.noise_figure`).
* :func:`displacement_derivatives` - carriage position, velocity and acceleration from a measured
  noisy displacement with no phase lag and controlled noise amplification.

End effects
-----------
Zero-phase filters distort the first and last ~0.5 s of a record when the signal is padded by
reflection (``sosfiltfilt``'s odd padding makes the second derivative jump at the end point
unless the signal's curvature happens to vanish there). Here each end is instead *extended* by a
model fitted to the last ``max(1 s, 2 periods)`` of data: a straight line plus a sinusoid and
its 2nd and 3rd harmonics, at the local frequency found by a least-squares search. The filter
runs over the extended signal and the extension is cut off again, so the ends see the same
filter as the middle of the record. Limitation: a strong component above the cutoff that the
end model does not hold (e.g. a 30 Hz tone) leaks partly into the end fit; the first and last
samples then carry an error of order 10% of that component's amplitude.

SciPy's ``signal``, ``stats``, ``optimize`` and ``interpolate`` are imported inside the
functions that use them: loading and checking a case file does not pay their 1.5-2 s import.
"""

from .derivatives import displacement_derivatives, motion_band, significant_frequencies
from .filters import lowpass
from .noise import noise_level, remove_tones, starts_quiet
from .noise_figure import NoiseFigure, quiet_segments, residual_noise, segment_noise
from .spectra import (
                      DriveCheck,
                      Peak,
                      Spectrum,
                      check_drive_frequency,
                      dominant_frequency,
                      drive_frequency,
                      find_spectral_peaks,
                      welch_spectrum,
)

__all__ = [
    "DriveCheck",
    "NoiseFigure",
    "Peak",
    "Spectrum",
    "check_drive_frequency",
    "displacement_derivatives",
    "dominant_frequency",
    "drive_frequency",
    "find_spectral_peaks",
    "lowpass",
    "motion_band",
    "noise_level",
    "quiet_segments",
    "remove_tones",
    "residual_noise",
    "segment_noise",
    "significant_frequencies",
    "starts_quiet",
    "welch_spectrum",
]
