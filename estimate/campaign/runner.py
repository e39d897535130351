"""Run a campaign: every record's fit (and diagnosis), then one fit per group without its
outliers, on an executor, each result stored under the key of its inputs as it arrives.

Two stages: the records first, since a group is fitted without the records that disagree
with it (:mod:`estimate.campaign.outliers`), which only the records' fits tell. Within a stage
the longest tasks start first. A result already in the store is taken from it (unless
``recompute``) when it passes its checksum and the check of its layout
(:func:`estimate.campaign.tasks.check_outcome`), else it is computed again with a warning.
A failure is stored only when it depends on the inputs alone; one caused by the environment
runs again next time. A record whose fit failed is left out of its group's fit, which uses
the others. An interrupted run loses only the tasks that were running. Cases are loaded
here, only for tasks that run, and shipped to the workers, so a remote cluster needs no
shared file system.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from analogs.errors import InputError

from ..data.case import Case
from ..data.reader import load_case
from ..executor import Executor, LocalExecutor
from .discovery import Campaign, Record
from .outliers import Outlier, find_outliers
from .progress import Progress
from .store import Store, task_key
from .tasks import Task, check_outcome, run_task

__all__ = ["CampaignRun", "run_campaign"]

#: Relative cost of a diagnosis against a fit of the same samples (about a dozen fits).
_DIAGNOSIS_COST = 12


@dataclass(frozen=True)
class CampaignRun:
    """Outcomes of a campaign run (JSON-ready dicts, see :func:`estimate.campaign.tasks.run_task`).

    Attributes
    ----------
    campaign : Campaign
        What was run (:func:`~estimate.campaign.discover`).
    records, diagnoses : dict
        Fit and diagnosis outcome by record id (diagnoses empty unless asked for).
    groups : dict
        Fit outcome by group name, with ``members`` (fitted) and ``excluded``
        (record id -> why it was left out).
    outliers : list of Outlier
    threshold : float
        Standard errors beyond which a record is an outlier.
    computed, reused, failed : int
        Tasks run now, taken from the store, and failed (of those run now or loaded).
    seconds : float
        Wall time of the run.
    """

    campaign: Campaign
    records: dict[str, dict[str, Any]]
    groups: dict[str, dict[str, Any]]
    diagnoses: dict[str, dict[str, Any]]
    outliers: list[Outlier]
    threshold: float
    computed: int
    reused: int
    failed: int
    seconds: float


def _one_line(text: str) -> str:
    return " ".join(part.strip() for part in str(text).splitlines() if part.strip())


class _Runner:
    def __init__(self, campaign: Campaign, store: Store, executor: Executor, progress: Progress,
                 *, recompute: bool = False, strict: bool = False) -> None:
        self.campaign, self.store, self.executor, self.progress = campaign, store, executor, progress
        self.recompute, self.strict = recompute, strict
        self.options = {"input": campaign.input}
        self.loaded: dict[str, Case | str] = {}      # record id -> case, or why it failed
        self.outcomes: dict[str, dict[str, Any]] = {}  # key -> outcome of this run
        self.work: dict[str, float] = {}               # key -> work, for the time left
        self.computed = self.reused = self.failed = 0

    def files(self, ids: Sequence[str]) -> list[tuple[str | None, str | None]]:
        return [(self.campaign.record(i).toml_sha256, self.campaign.record(i).data_sha256)
                for i in ids]

    def work_of(self, kind: str, ids: Sequence[str]) -> float:
        """A task's work for the progress display: the bytes of data it fits."""
        data = sum(self.campaign.record(i).data_bytes for i in ids)
        return float(data * (_DIAGNOSIS_COST if kind == "diagnosis" else 1))

    def load(self, record: Record) -> Case | str:
        if record.id not in self.loaded:
            try:
                self.loaded[record.id] = load_case(record.path, strict=self.strict)
            except InputError as err:
                self.loaded[record.id] = _one_line(err)
        return self.loaded[record.id]

    def run(self, wanted: Sequence[tuple[str, str, tuple[str, ...], str | None]]
            ) -> dict[str, dict[str, Any]]:
        """Outcomes of ``(kind, label, record ids, model)`` tasks by key: from the store,
        from a failed load, or computed now."""
        keys = [self.key_of(*w) for w in wanted]
        new = {k: w for k, w in zip(keys, wanted) if k not in self.outcomes}
        self.work.update({k: self.work_of(w[0], w[2]) for k, w in new.items()})
        self.progress.expect(len(new), sum(self.work[k] for k in new))
        tasks: dict[str, Task] = {}
        for key, (kind, label, ids, model) in zip(keys, wanted):
            if key in tasks or key in self.outcomes:
                continue
            stored = None if self.recompute else self.store.get(
                key, check=lambda outcome, kind=kind: check_outcome(kind, outcome))
            if stored is not None:
                self.outcomes[key] = stored
                self.reused += 1
                self.progress.from_store(1, self.work[key])
                continue
            cases = [self.load(self.campaign.record(i)) for i in ids]
            bad = [f"{i}: {c}" for i, c in zip(ids, cases) if isinstance(c, str)]
            if bad:    # not stored: loading again costs little and tells the same
                self.outcomes[key] = {"status": "failed", "error": "; ".join(bad), "stage": "load",
                                      "failure": "inputs"}
                self.failed += 1
                self.progress.submit(1)
                self.progress.finish(False, 0.0, self.work[key])
                continue
            tasks[key] = Task(kind, key, label, tuple(cases), model, self.campaign.input)
        self._execute(sorted(tasks.values(), key=self._cost))
        return {key: self.outcomes[key] for key in keys}

    def key_of(self, kind: str, label: str, ids: tuple[str, ...], model: str | None) -> str:
        """The store key of a task: its kind, its records' files, the model spec and,
        for fits, the campaign's options (``label`` only names it)."""
        return task_key(kind, self.files(ids), model, self.options if kind == "fit" else {})

    @staticmethod
    def _cost(task: Task) -> tuple[float, str]:
        samples = sum(c.n_samples for c in task.cases)
        return (-samples * (_DIAGNOSIS_COST if task.kind == "diagnosis" else 1), task.key)

    def _execute(self, tasks: list[Task]) -> None:
        if not tasks:
            return
        self.progress.submit(len(tasks))
        with closing(self.executor.as_completed(run_task, tasks)) as done:
            for i, future in done:
                task = tasks[i]
                try:
                    outcome = future.result()
                except Exception as err:  # noqa: BLE001 - a worker died: retried next run
                    outcome = {"status": "failed", "failure": "environment",
                               "error": _one_line(f"{type(err).__name__}: {err}"), "seconds": 0.0}
                seconds = float(outcome.pop("seconds", 0.0))
                if outcome["status"] != "failed" or outcome.get("failure") == "inputs":
                    self.store.put(task.key, outcome, seconds=seconds)
                self.outcomes[task.key] = outcome
                self.computed += 1
                self.failed += outcome["status"] == "failed"
                self.progress.finish(outcome["status"] != "failed", seconds, self.work[task.key])


def run_campaign(campaign: Campaign, out: str | Path, *, executor: Executor | None = None,
                 diagnose: bool = False, progress: bool | None = None, recompute: bool = False,
                 strict: bool = False) -> CampaignRun:
    """Fit (and diagnose) every record of ``campaign``, then each group without its outliers.

    Parameters
    ----------
    campaign : Campaign
        From :func:`estimate.campaign.discover`.
    out : path
        Campaign output folder; results are stored in ``out/store``.
    executor : Executor, optional
        Where tasks run (:mod:`estimate.executor`); default a :class:`LocalExecutor`.
    diagnose : bool, default False
        Also diagnose every record (:func:`estimate.diagnosis.diagnose`).
    progress : bool, optional
        Show campaign progress on stderr; default when stderr is a terminal.
    recompute : bool, default False
        Compute every task again (``--overwrite``) instead of taking stored results.
    strict : bool, default False
        Refuse case files with unknown keys (``--strict``) instead of warning.

    Returns
    -------
    CampaignRun

    Examples
    --------
    >>> run = run_campaign(discover("examples/campaign"), "campaign")   # doctest: +SKIP
    """
    t0 = time.perf_counter()
    executor = executor or LocalExecutor()
    bar = Progress(executor.workers, enabled=progress)
    runner = _Runner(campaign, Store(Path(out) / "store"), executor, bar, recompute=recompute,
                     strict=strict)
    ids = [r.id for r in campaign.records]
    try:
        # the groups' fits come once the records' are known; count them from the start
        bar.plan(len(campaign.groups), sum(runner.work_of("fit", g.records)
                                           for g in campaign.groups))
        stage = [("fit", f"record {i}", (i,), campaign.model_of(i)) for i in ids]
        if diagnose:
            stage += [("diagnosis", f"diagnosis {i}", (i,), None) for i in ids]
        done = runner.run(stage)
        records = {w[2][0]: done[runner.key_of(*w)] for w in stage if w[0] == "fit"}
        diagnoses = {w[2][0]: done[runner.key_of(*w)] for w in stage if w[0] == "diagnosis"}
        outliers, threshold = find_outliers([(g.name, g.records) for g in campaign.groups],
                                            records)
        flagged = {o.record for o in outliers}
        groups, excluded = [], {}
        for g in campaign.groups:
            excluded[g.name] = {i: ("outlier" if i in flagged else "failed to load"
                                    if records[i].get("stage") == "load" else "its fit failed")
                                for i in g.records if i in flagged
                                or records[i].get("status") == "failed"}
            members = tuple(i for i in g.records if i not in excluded[g.name])
            if members:
                groups.append((g.name, ("fit", f"group {g.name}", members, g.model)))
        bar.plan(0)
        fitted = runner.run([w for _, w in groups])
    finally:
        bar.close()
    group_out = {}
    for g in campaign.groups:
        wanted = next((w for name, w in groups if name == g.name), None)
        outcome = dict(fitted[runner.key_of(*wanted)]) if wanted else {
            "status": "failed", "error": "no record of the group can be fitted",
            "failure": "inputs"}
        outcome["members"] = list(wanted[2]) if wanted else []
        outcome["excluded"] = excluded[g.name]
        group_out[g.name] = outcome
    return CampaignRun(campaign, records, group_out, diagnoses, outliers, threshold,
                       runner.computed, runner.reused, runner.failed, time.perf_counter() - t0)
