"""A campaign's records and groups: the case files of a folder or glob, the optional
``campaign.toml``, and the groups whose records share their physical parameters in one
multi-case fit.

Without groups in ``campaign.toml``, records are grouped by their ``[tank]`` and
``[liquid]`` tables and rig: the same tank at the same fill with the same liquid on the same
rig, across drives and amplitudes, is one group. ``campaign.toml`` (in the folder, or in the
top folder of a glob pattern) may give a title, a note, the model and explicit groups::

    [campaign]
    title = "8-inch sphere, water"
    note = "SYNTHETIC data"
    model = "fixed,p1:nospring"     # default: the model of `slosh fit`
    input = "estimated"             # or "filtered" (see `slosh fit --input`)

    [groups.low]                    # optional; then only these groups
    records = ["F40_*"]             # record ids or case files (globs, relative to this file)
    model = "fixed,p1"              # optional, this group's model

Only the file's bytes are read here (parsed as TOML for ids and grouping keys); the cases are
validated when they are loaded for fitting, and a record that fails then fails alone.
"""

from __future__ import annotations

import fnmatch
import glob
import hashlib
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from analogs.errors import InputError

from ..data.case import SHAPE_KEYS
from ..data.models import BASELINE
from ..data.reader import MAX_CASE_FILE_BYTES
from ..fitting.strategies import DEFAULT_INPUT, INPUT_MODES
from ..inputs import file_kind, load_toml, open_input
from .catalogue import Campaign, Group, Record, Setup

__all__ = ["CAMPAIGN_FILE", "Campaign", "Group", "Record", "Setup", "discover"]

#: The campaign description file looked for in the campaign folder.
CAMPAIGN_FILE = "campaign.toml"
_CAMPAIGN_KEYS = {"title", "note", "model", "input"}
_GROUP_KEYS = {"records", "model"}


def _sha256(path: Path) -> str | None:
    """SHA-256 of a regular file's bytes; None for anything else (a pipe or a device is
    never opened for reading: loading the record says what it is)."""
    try:
        with open_input(path, "a data file") as fh:
            return hashlib.file_digest(fh, "sha256").hexdigest()
    except (OSError, InputError):
        return None


def _read_toml(path: Path) -> dict[str, Any] | None:
    try:
        return load_toml(path, "a TOML case file", limit=MAX_CASE_FILE_BYTES)
    except (OSError, InputError):
        return None


def _setup(doc: Mapping[str, Any]) -> Setup | None:
    try:
        test, tank, liquid, rig = (doc[k] for k in ("test", "tank", "liquid", "rig"))
        shape = str(tank["shape"])
        sizes = tuple((k, float(tank[k])) for k in SHAPE_KEYS.get(shape, ("radius",))
                      if k != "radius")
        return Setup(rig=str(test.get("rig", "lateral")), shape=shape,
                     radius=float(tank.get("radius", math.nan)), sizes=sizes,
                     fill_fraction=float(tank["fill_fraction"]),
                     diaphragm=bool(tank.get("diaphragm", False)),
                     density=float(liquid["density"]),
                     viscosity=float(liquid["kinematic_viscosity"]),
                     gravity=float(rig.get("gravity", 9.80665)))
    except (KeyError, TypeError, ValueError, AttributeError):
        return None


def _case_files(source: str) -> tuple[Path, list[Path]]:
    """The campaign folder and the TOML files of ``source`` (a folder or a glob)."""
    src = Path(source)
    if src.is_dir():
        return src.resolve(), sorted(p for p in src.rglob("*.toml") if p.is_file())
    if not glob.has_magic(source):
        raise InputError(f"{source}: no such folder (expected a folder of case files or a glob "
                         "such as `tests/*.toml`)")
    parts = Path(source).parts
    top = Path(*[p for p in parts[:next(i for i, p in enumerate(parts) if glob.has_magic(p))]]
               or ["."])
    return top.resolve(), sorted(Path(p) for p in glob.glob(source, recursive=True)
                                 if p.endswith(".toml") and Path(p).is_file())


def _record(path: Path, root: Path) -> Record | None:
    doc = _read_toml(path)
    if doc is not None and not isinstance(doc.get("test"), Mapping):
        return None                                  # a TOML file, not a case file
    test = doc["test"] if doc is not None else {}
    rid = test.get("id") if isinstance(test.get("id"), str) and test.get("id") else path.stem
    data = test.get("data")
    data_sha, data_bytes = None, 0
    if isinstance(data, str) and data.strip():
        data_sha = _sha256(path.parent / data)
        if data_sha is not None:
            data_bytes = os.stat(path.parent / data).st_size
    try:
        rel = path.resolve().relative_to(root).as_posix()
    except ValueError:
        rel = str(path.resolve())
    return Record(rid, path.resolve(), rel, _sha256(path), data_sha,
                  _setup(doc) if doc is not None else None, data_bytes)


def _group_names(keys: list[Setup]) -> list[str]:
    """Readable unique names: shape, radius and fill, plus what else varies."""
    varying = [f for f in ("rig", "diaphragm", "density", "viscosity", "gravity")
               if len({getattr(k, f) for k in keys}) > 1]
    names = []
    for k in keys:
        name = f"{k.shape}-{k.size_name}-fill{k.fill_fraction:g}"
        for f in varying:
            v = getattr(k, f)
            name += (f"-{v}" if f == "rig" else "-diaphragm" if f == "diaphragm" and v
                     else "" if f == "diaphragm" else f"-{f}{v:g}")
        names.append(name)
    return names


def _groups_by_keys(records: tuple[Record, ...], model: str) -> tuple[Group, ...]:
    by_key: dict[Setup, list[str]] = {}
    for r in records:
        if r.setup is not None:
            by_key.setdefault(r.setup, []).append(r.id)
    keys = sorted(by_key, key=lambda k: (k.series, k.fill_fraction))
    return tuple(Group(name, tuple(sorted(by_key[k])), model)
                 for name, k in zip(_group_names(keys), keys))


def _explicit_groups(doc: Mapping[str, Any], fname: str, records: tuple[Record, ...],
                     model: str, problems: list[str]) -> tuple[Group, ...]:
    groups: list[Group] = []
    owner: dict[str, str] = {}
    for name, table in doc.items():
        where = f"{fname}: [groups.{name}]"
        if not isinstance(table, Mapping):
            problems.append(f"{where}: expected a table with `records`, found {table!r}")
            continue
        for key in sorted(set(table) - _GROUP_KEYS):
            problems.append(f"{where}: unknown key `{key}`{_nearest(key, _GROUP_KEYS)}")
        pats = table.get("records")
        if not (isinstance(pats, list) and pats and all(isinstance(p, str) for p in pats)):
            problems.append(f"{where} records: expected a list of record ids or case-file "
                            f"globs, found {pats!r}")
            continue
        gm = table.get("model", model)
        if not isinstance(gm, str) or not gm.strip():
            problems.append(f"{where} model: expected a model specification such as "
                            f"\"fixed,p1\", found {gm!r}")
        elif "model" in table:
            problems += _spec_problems(gm, f"{where} model", [r for r in records])
        members = []
        for pat in pats:
            hit = [r.id for r in records
                   if fnmatch.fnmatchcase(r.id, pat) or fnmatch.fnmatchcase(r.relpath, pat)]
            if not hit:
                problems.append(f"{where} records: {pat!r} matches no record")
            members += [h for h in hit if h not in members]
        for m in members:
            if m in owner:
                problems.append(f"{where}: record {m!r} is already in group {owner[m]!r}")
            owner.setdefault(m, name)
        groups.append(Group(name, tuple(sorted(members)), gm if isinstance(gm, str) else model))
    return tuple(groups)


def _settings(path: Path, records: tuple[Record, ...]) -> tuple[dict[str, Any], tuple[Group, ...]
                                                                 | None]:
    """``[campaign]`` settings and the explicit groups of ``campaign.toml`` (None: group by
    keys); every problem of the file is reported at once."""
    if not path.exists() and not path.is_symlink():
        return {}, None
    if file_kind(path):
        raise InputError(f"{path}: expected the campaign file (TOML), found {file_kind(path)}")
    doc = load_toml(path, "the campaign file (TOML)", limit=MAX_CASE_FILE_BYTES)
    fname, problems = path.name, []
    for key in sorted(set(doc) - {"campaign", "groups"}):
        problems.append(f"{fname}: unknown table `[{key}]`"
                        f"{_nearest(key, {'campaign', 'groups'}, table=True)}")
    settings = doc.get("campaign", {})
    if not isinstance(settings, Mapping):
        problems.append(f"{fname}: [campaign]: expected a table")
        settings = {}
    for key in sorted(set(settings) - _CAMPAIGN_KEYS):
        problems.append(f"{fname}: [campaign]: unknown key `{key}`{_nearest(key, _CAMPAIGN_KEYS)}")
    for key in sorted(_CAMPAIGN_KEYS & set(settings)):
        if not isinstance(settings[key], str):
            problems.append(f"{fname}: [campaign] {key}: expected a string, found "
                            f"{settings[key]!r}")
    if settings.get("input", DEFAULT_INPUT.name) not in INPUT_MODES:
        problems.append(f"{fname}: [campaign] input: expected one of "
                        f"{', '.join(INPUT_MODES)}, found {settings['input']!r}")
    if isinstance(settings.get("model"), str):
        problems += _spec_problems(settings["model"], f"{fname}: [campaign] model", records)
    groups = None
    if "groups" in doc:
        model = settings.get("model") if isinstance(settings.get("model"), str) else BASELINE
        raw = doc["groups"]
        if not isinstance(raw, Mapping) or not raw:
            problems.append(f"{fname}: groups: expected tables `[groups.NAME]` with `records = "
                            f"[...]`, found {raw!r}"[:300])
            raw = {}
        groups = _explicit_groups(raw, fname, records, model, problems)
    if len(problems) == 1:  # one line, as every other input error
        raise InputError(problems[0])
    if problems:
        raise InputError(f"{len(problems)} problems in the campaign file:\n"
                         + "\n".join(f"  - {p}" for p in problems))
    return dict(settings), groups


def _nearest(key: str, known: set[str], *, table: bool = False) -> str:
    """`` (did you mean `records`?)`` for a key close to a known one, else the known keys."""
    import difflib

    near = difflib.get_close_matches(key, sorted(known), n=1, cutoff=0.6)
    fmt = "[{}]" if table else "{}"
    if near:
        return f"; did you mean `{fmt.format(near[0])}`?"
    return f" (known: {', '.join(fmt.format(k) for k in sorted(known))})"


def _spec_problems(spec: str, where: str, records) -> list[str]:
    """Why the model specification ``spec`` (from ``where``) cannot be built for the rigs of
    ``records`` (checked at discovery, so that the key that gave it is named)."""
    from analogs import LateralRig, SpinningRig
    from analogs.spec import model_from_spec

    rigs = sorted({r.setup.rig for r in records if r.setup is not None} & {"lateral", "spinning"})
    for rig in rigs or ["lateral"]:
        on = (SpinningRig(gravity=True, tank_axis="spin", motion="constant") if rig == "spinning"
              else LateralRig(excitation="measured"))
        try:
            model_from_spec(spec, on, option=where)
        except InputError as err:
            return [str(err)]
    return []


def discover(source: str, *, model: str | None = None) -> Campaign:
    """The records and groups of a campaign.

    Parameters
    ----------
    source : str
        A folder (its ``*.toml`` case files, searched recursively, and its
        ``campaign.toml``) or a glob pattern of case files (``"tests/**/*.toml"``; a
        ``campaign.toml`` in the pattern's top folder is used).
    model : str, optional
        Model specification for every record and group, over those of ``campaign.toml``.

    Returns
    -------
    Campaign

    Raises
    ------
    InputError
        No case file found, two case files with the same ``[test] id``, or problems in
        ``campaign.toml`` (all listed at once).

    Examples
    --------
    >>> campaign = discover("examples/campaign")          # doctest: +SKIP
    >>> [g.name for g in campaign.groups]                 # doctest: +SKIP
    ['sphere-R0.1016-fill0.4', 'sphere-R0.1016-fill0.6', 'sphere-R0.1016-fill0.8']
    """
    root, files = _case_files(source)
    settings_file = root / CAMPAIGN_FILE
    files = [f for f in files if f.resolve() != settings_file]
    found = [(f, _record(f, root)) for f in files]
    records = tuple(sorted((r for _, r in found if r is not None), key=lambda r: r.id))
    skipped = tuple(str(f) for f, r in found if r is None)
    if not records:
        raise InputError(f"{source}: no case files (TOML files with a [test] table) found")
    seen: dict[str, list[str]] = {}
    for r in records:
        seen.setdefault(r.id, []).append(r.relpath)
    dupes = {k: v for k, v in seen.items() if len(v) > 1}
    if dupes:
        raise InputError("record ids must be unique in a campaign; "
                         + "; ".join(f"[test] id {k!r} in {', '.join(v)}" for k, v in dupes.items()))
    if model is not None:
        bad = _spec_problems(model, "--model", records)
        if bad:
            raise InputError(bad[0])
    settings, groups = _settings(settings_file, records)
    spec = model or settings.get("model") or BASELINE
    if groups is None:
        groups = _groups_by_keys(records, spec)
    elif model is not None:
        groups = tuple(Group(g.name, g.records, model) for g in groups)
    return Campaign(source=str(source), root=root, title=settings.get("title", ""),
                    note=settings.get("note", ""), model=spec,
                    input=settings.get("input", DEFAULT_INPUT.name), records=records, groups=groups,
                    skipped=skipped)
