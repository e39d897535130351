"""Output files of the ``slosh`` commands: nothing existing is replaced unless asked."""

from __future__ import annotations

from pathlib import Path
from typing import Iterable

__all__ = ["refuse_existing"]


def refuse_existing(paths: Iterable[str | Path | None], overwrite: bool) -> None:
    """Raise FileExistsError naming every existing file in ``paths`` (``None`` and "" skipped)
    unless ``overwrite`` is true."""
    existing = [str(p) for p in paths if p and Path(p).exists()]
    if existing and not overwrite:
        raise FileExistsError(f"{', '.join(existing)} exist(s); pass --overwrite to replace")
