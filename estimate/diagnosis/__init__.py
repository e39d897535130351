"""Diagnosis: what a fitted analog gets wrong (evidence), which extensions could explain it
(candidates), the held-out search that accepts them, and the report."""

from .search import Diagnosis, Finding, diagnose

__all__ = ["Diagnosis", "Finding", "diagnose", "before_after_figure", "residual_spectra_figure",
           "write_report"]
_REPORT = ("before_after_figure", "residual_spectra_figure", "write_report")


def __getattr__(name: str):
    """The report's figures and writer (:mod:`estimate.diagnosis.report`:
    ``before_after_figure``, ``residual_spectra_figure``, ``write_report``), imported when
    first used (they bring matplotlib)."""
    if name in _REPORT:
        from . import report

        return getattr(report, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
