"""The work of a campaign, one task at a time, on whichever worker runs it: a fit of one
record or of a group, or the diagnosis of one record. A task returns a JSON-ready outcome
and does not raise for its own errors, so one bad record never stops the others.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analogs.errors import InputError

from ..data.case import Case
from ..fitting.strategies import DEFAULT_INPUT

__all__ = ["FAILURE_CAUSES", "Task", "check_outcome", "drive_amplitude", "found_quantities",
           "run_task"]

#: Why a task failed, as its outcome's ``failure`` says: ``"inputs"`` (the case files, data
#: or model: stored, and not retried until they change) or ``"environment"`` (the machine,
#: a library, a worker: not stored, retried on the next run).
FAILURE_CAUSES = {"inputs": "depends only on the inputs: kept until they change",
                  "environment": "not caused by the inputs: retried on the next run"}
_STATUSES = ("ok", "not_converged", "failed")

#: Level of the intervals in the campaign table (the fit report's 95 %).
LEVEL = 0.95


@dataclass(frozen=True)
class Task:
    """A unit of campaign work.

    Attributes
    ----------
    kind : {"fit", "diagnosis"}
    key : str
        Store key of its inputs (:func:`estimate.campaign.store.task_key`).
    label : str
        What it is, for messages: ``"record F40_sine_1.5mm"``, ``"group fill40"``.
    cases : tuple of Case
        The loaded cases, in fitting order.
    model : str or None
        Model specification (``None`` for a diagnosis: it starts from its baseline).
    input : str
        How a measured carriage displacement enters the fit (``FitProblem.build(input=)``).
    """

    kind: str
    key: str
    label: str
    cases: tuple[Case, ...] = field(repr=False)
    model: str | None
    input: str = DEFAULT_INPUT.name


def drive_amplitude(case: Case) -> float:
    """Amplitude of the carriage motion (m): half the spread between the 0.5 and 99.5
    percentiles of the measured displacement (robust to noise spikes), or the crank radius
    of a crank-driven case; NaN for a spinning-rig case."""
    if case.displacement is not None:
        lo, hi = np.percentile(case.displacement, [0.5, 99.5])
        return float(hi - lo) / 2
    if case.crank is not None:
        return float(case.crank.radius)
    return math.nan


def _own_arrays(case: Case) -> Case:
    """``case`` with private aligned copies of its arrays (read-only, as loaded). Dask hands
    arrays to a worker without copying them, possibly unaligned in its message buffer, and
    SciPy's B-spline design matrix rejects unaligned arrays."""
    def own(a):
        if a is None:
            return None
        b = np.array(a, dtype=float, order="C", copy=True)
        b.flags.writeable = False
        return b

    return dataclasses.replace(case, time=own(case.time), displacement=own(case.displacement),
                               force=own(case.force),
                               columns={k: own(v) for k, v in case.columns.items()})


def _quantities(result) -> tuple[dict[str, list], dict[str, list]]:
    """Shared estimates and derived quantities as ``[value, stderr, lo, hi, unit]``."""
    from scipy.stats import t as student

    q = float(student.ppf(0.5 + LEVEL / 2, result.dof))
    params = {}
    for e, v, se in zip(result.problem.estimated, result.values, result.stderr):
        if e.case is None:          # per-case crank corrections stay out of the table
            lo, hi = result.interval(e.name, LEVEL)
            params[e.name] = [float(v), float(se), lo, hi, e.unit]
    derived = {k: [v, se, v - q * se, v + q * se, result.derived_units.get(k, "")]
               for k, (v, se) in result.derived.items()}
    return params, derived


def _fit(task: Task) -> dict[str, Any]:
    from ..data.decimation import slosh_band_decimated
    from ..data.models import model_from_spec
    from ..fitting.nlp import fit
    from ..fitting.problem import FitProblem

    cases = [slosh_band_decimated(c) for c in task.cases]  # as `slosh fit` does
    model = model_from_spec(task.model, cases[0])
    result = fit(FitProblem.build(cases, model, input=task.input), progress=False)
    params, derived = _quantities(result)
    # each record's noise figure, the one the fit report and the diagnosis print
    noise = [f.std if (f := result.noise_figure(i)) is not None else math.nan
             for i in range(len(cases))]
    n = [int(c.n_samples) for c in cases]
    pooled = math.sqrt(sum(k * s**2 for k, s in zip(n, noise)) / sum(n))
    return {
        "status": "ok" if result.converged else "not_converged",
        "error": None if result.converged else f"IPOPT: {result.status}",
        "cases": [c.test.id for c in cases], "model": task.model,
        "solver_status": result.status, "iterations": int(result.iterations),
        "samples": sum(n), "rms_residual": float(result.rms_residual), "noise": pooled,
        "parameters": params, "derived": derived,
        "records": {c.test.id: {"amplitude_m": drive_amplitude(c), "samples": k,
                                "force_noise": s} for c, k, s in zip(cases, n, noise)},
        "warnings": list(result.warnings),
    }


def _diagnosis(task: Task) -> dict[str, Any]:
    from ..diagnosis.search import diagnose

    d = diagnose(list(task.cases))
    findings = [{"cause": f.cause, "added": list(f.added), "gain": f.gain,
                 "bic_change": f.bic_change} for f in d.findings]
    verdict = ("; ".join(f"{f['cause']} (+{', '.join(f['added'])})" for f in findings)
               or "no finding")
    params, derived = _quantities(d.final)
    return {"status": "ok", "error": None, "cases": [c.test.id for c in task.cases],
            "verdict": verdict, "findings": findings,
            "final_model": list(d.final.problem.model.names),
            "final_parameters": params, "final_derived": derived,
            "rms_baseline": float(d.baseline.rms_residual),
            "rms_final": float(d.final.rms_residual), "notes": list(d.notes)}


def run_task(task: Task, shared: Any = None) -> dict[str, Any]:
    """Run ``task`` and return its outcome: ``status`` (``"ok"``, ``"not_converged"`` or
    ``"failed"``), ``error`` (None or one line), ``seconds`` and the task's results.

    A failure says its cause in ``failure`` (:data:`FAILURE_CAUSES`): an error in what the
    user gave (:class:`~analogs.errors.InputError`: a bad model specification, a case the
    model cannot fit) depends only on the inputs and is stored like a result; anything else
    (out of memory, a file-system error, a missing library, a solver crash) is the
    environment's, is not stored and runs again next time. ``shared`` is unused (the
    executor interface passes it).
    """
    t0 = time.perf_counter()
    try:
        task = dataclasses.replace(task, cases=tuple(_own_arrays(c) for c in task.cases))
        outcome = _fit(task) if task.kind == "fit" else _diagnosis(task)
    except InputError as err:
        outcome = {"status": "failed", "error": str(err).replace("\n", " "), "failure": "inputs"}
    except MemoryError as err:
        outcome = {"status": "failed", "error": f"out of memory: {err}", "failure": "environment"}
    except Exception as err:  # noqa: BLE001 - reported in the table, the others go on
        outcome = {"status": "failed", "error": f"{type(err).__name__}: {err}".replace("\n", " "),
                   "failure": "environment"}
    outcome["seconds"] = time.perf_counter() - t0
    return outcome


def _numbers(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _quantity_rows(table: Any) -> bool:
    return isinstance(table, dict) and all(
        isinstance(k, str) and isinstance(v, list) and len(v) == 5
        and all(_numbers(x) for x in v[:4]) and isinstance(v[4], str) for k, v in table.items())


def check_outcome(kind: str, outcome: dict[str, Any]) -> str | None:
    """What is wrong with a stored outcome of a ``kind`` task (None: it has the layout
    :func:`run_task` writes): a status, an error line, and the results of its kind."""
    status = outcome.get("status")
    if status not in _STATUSES:
        return f"`status`: expected one of {', '.join(_STATUSES)}, found {status!r}"
    error = outcome.get("error")
    if error is not None and not isinstance(error, str):
        return f"`error`: expected a line of text or null, found {error!r}"
    if status == "failed":
        if not error:
            return "a failed outcome without its error"
        if outcome.get("failure") != "inputs":
            return "a stored failure that does not depend only on the inputs"
        return None
    cases = outcome.get("cases")
    if not (isinstance(cases, list) and cases and all(isinstance(c, str) for c in cases)):
        return f"`cases`: expected a list of record ids, found {cases!r}"
    if kind == "fit":
        if not (_quantity_rows(outcome.get("parameters")) and outcome["parameters"]):
            return "`parameters`: expected estimates as [value, stderr, lo, hi, unit]"
        if not _quantity_rows(outcome.get("derived")):
            return "`derived`: expected quantities as [value, stderr, lo, hi, unit]"
        for key in ("rms_residual", "noise", "samples", "iterations"):
            if not _numbers(outcome.get(key)):
                return f"`{key}`: expected a number, found {outcome.get(key)!r}"
        if not isinstance(outcome.get("records"), dict):
            return "`records`: expected an object by record id"
    else:
        if not isinstance(outcome.get("verdict"), str) or not isinstance(
                outcome.get("findings"), list):
            return "expected a diagnosis with `verdict` and `findings`"
        for key in ("final_parameters", "final_derived"):  # absent in entries of before
            if key in outcome and not _quantity_rows(outcome[key]):
                return f"`{key}`: expected quantities as [value, stderr, lo, hi, unit]"
    return None


def found_quantities(diagnosis: dict[str, Any]) -> dict[str, list]:
    """The final model's estimates and derived quantities of what a diagnosis outcome
    added (``p2.mass``, ``p2.frequency_hz`` for a finding ``+p2``), as ``[value, stderr,
    lo, hi, unit]``; empty without findings (or for an outcome stored before the final
    estimates were kept)."""
    added = [a for f in diagnosis.get("findings") or () for a in f.get("added") or ()]
    table = {**(diagnosis.get("final_parameters") or {}), **(diagnosis.get("final_derived") or {})}
    return {k: v for k, v in table.items()
            if any(k == a or k.startswith(f"{a}.") for a in added)}
