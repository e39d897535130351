"""The fit as a record an engineer keeps: the one home of the fit's JSON, its reader and its
report.

* :func:`fit_record` / :func:`fit_json` - a :class:`~estimate.fitting.FitResult` as the JSON
  that ``slosh fit --json`` writes (:data:`SCHEMA`, ``"schema": "slosh-analogs/fit/2"``):
  every estimate with its standard errors (robust and Gauss-Newton), 95 % interval, unit and
  bounds; the covariances; derived quantities; statistics with AIC and BIC
  (:func:`information_criteria`); noise figures; IPOPT's status; and the provenance
  (:func:`provenance`: package and solver versions, UTC date, each case and data file with
  its SHA-256, the command's options, the model specification as given).
* :func:`read_fit`, :func:`read_params`, :func:`fit_notes`, :func:`fitted_initial_state`,
  :func:`fit_spec` - what the commands that take a fit read from it; a record written before
  the schema was versioned still reads, with a note.
* :func:`report_text` / :func:`report_markdown` - the fit report (``slosh fit --report``,
  ``slosh fit --report FILE.md``).
* :func:`compare_fits` - two or more records side by side, with the differences in units of
  their combined standard errors (``slosh compare``).

Examples
--------
>>> from estimate.fitting.record import fit_json, fit_record, read_fit     # doctest: +SKIP
>>> record = fit_record(result, model_spec="fixed,p1")        # doctest: +SKIP
>>> _ = open("fit.json", "w").write(fit_json(record))          # doctest: +SKIP
>>> read_fit("fit.json").intervals["p1.mass"]                   # doctest: +SKIP
(1.2958, 1.3044)
"""

from .compare import Comparison, Quantity, compare_fits
from .parameters import (
    fit_notes,
    fit_spec,
    fitted_initial_state,
    read_json,
    read_params,
    schema_version,
)
from .provenance import file_sha256, provenance, versions
from .reader import Fit, read_fit
from .text import report_markdown, report_text
from .writer import SCHEMA, fit_json, fit_record, information_criteria

__all__ = ["SCHEMA", "Comparison", "Fit", "Quantity", "compare_fits", "file_sha256", "fit_json",
           "fit_notes", "fit_record", "fit_spec", "fitted_initial_state", "information_criteria",
           "provenance", "read_fit", "read_json", "read_params", "report_markdown", "report_text",
           "schema_version", "versions"]
