"""What a campaign's discovery finds (:func:`estimate.campaign.discovery.discover`): each
record with its setup (:class:`Record`, :class:`Setup`), the groups fitted together
(:class:`Group`) and the whole (:class:`Campaign`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Campaign", "Group", "Record", "Setup"]


@dataclass(frozen=True)
class Setup:
    """What makes records one group: ``rig`` kind, ``[tank]`` (``shape``, ``radius`` in m -
    NaN for a rectangular tank -, ``fill_fraction``, ``diaphragm``, the shape's other
    ``sizes`` in m) and ``[liquid]`` (``density`` in kg/m^3, kinematic ``viscosity`` in
    m^2/s), and ``[rig] gravity`` (``gravity``, m/s^2) for the tank prediction."""

    rig: str
    shape: str
    radius: float
    fill_fraction: float
    diaphragm: bool
    density: float
    viscosity: float
    gravity: float
    #: ``[tank]`` sizes besides the radius (``(("length", 0.3),)`` for a cylinder), m.
    sizes: tuple[tuple[str, float], ...] = ()

    @property
    def series(self) -> tuple:
        """The setup without the fill: records of one series lie on one prediction curve."""
        return (self.rig, self.shape, self.radius, self.sizes, self.diaphragm, self.density,
                self.viscosity, self.gravity)

    def geometry(self):
        """The tank as an :mod:`analogs.tank` geometry (see
        :meth:`estimate.data.case.Tank.geometry`)."""
        from ..data.case import Tank

        radius = None if math.isnan(self.radius) else self.radius
        return Tank(self.shape, radius, self.fill_fraction, self.diaphragm,
                    **dict(self.sizes)).geometry()

    @property
    def size_name(self) -> str:
        """``R0.1016`` (axisymmetric), ``0.4x0.2x0.3`` (rectangular), plus other sizes."""
        head = [] if math.isnan(self.radius) else [f"R{self.radius:g}"]
        if self.shape == "rectangular":
            return "x".join(f"{v:g}" for _, v in self.sizes)
        return "-".join(head + [f"{k}{v:g}" for k, v in self.sizes])


@dataclass(frozen=True)
class Record:
    """One case file of the campaign.

    Attributes
    ----------
    id : str
        ``[test] id`` (the file name without ``.toml`` when the file cannot be read).
    path : pathlib.Path
        The case file, resolved.
    relpath : str
        The case file relative to the campaign folder (POSIX separators).
    toml_sha256, data_sha256 : str or None
        SHA-256 of the case file's and of its data file's bytes (None: not readable).
    setup : Setup or None
        The grouping keys, None when the file does not give them all (the record is then
        in no group; loading it reports what is wrong).
    data_bytes : int
        Size of the data file (0: not readable), the measure of a task's work for the
        campaign's time left.
    """

    id: str
    path: Path
    relpath: str
    toml_sha256: str | None
    data_sha256: str | None
    setup: Setup | None
    data_bytes: int = 0


@dataclass(frozen=True)
class Group:
    """Records fitted together (shared physical parameters) with ``model``: the group's
    ``name`` and its ``records`` (ids)."""

    name: str
    records: tuple[str, ...]
    model: str


@dataclass(frozen=True)
class Campaign:
    """A discovered campaign (see :func:`discover`).

    Attributes
    ----------
    source : str
        The folder or glob given.
    root : Path
        The campaign folder (of ``campaign.toml``, and of the records' relative paths).
    title, note : str
        ``[campaign] title`` and ``note`` (empty when not given).
    model, input : str
        The campaign's model specification and carriage input mode.
    records : tuple of Record
        Every case file found, by path.
    groups : tuple of Group
        The groups fitted together.
    """

    source: str
    root: Path
    title: str
    note: str
    model: str
    input: str
    records: tuple[Record, ...]
    groups: tuple[Group, ...]
    #: TOML files that are not case files (no ``[test]`` table).
    skipped: tuple[str, ...] = ()

    def record(self, record_id: str) -> Record:
        """The record whose ``[test] id`` is ``record_id``."""
        return next(r for r in self.records if r.id == record_id)

    def group_of(self, record_id: str) -> Group | None:
        """The group of the record ``record_id``, or None (in no group)."""
        return next((g for g in self.groups if record_id in g.records), None)

    def model_of(self, record_id: str) -> str:
        """The model of the record ``record_id``: its group's, else the campaign's."""
        group = self.group_of(record_id)
        return group.model if group is not None else self.model
