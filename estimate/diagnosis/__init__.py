"""Diagnosis: what a fitted analog gets wrong (evidence), which extensions could explain it
(candidates), the held-out search that accepts them, and the report."""

from .search import Diagnosis, Finding, diagnose

__all__ = ["Diagnosis", "Finding", "diagnose"]
