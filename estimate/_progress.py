"""Progress bars for steps that can take more than a couple of seconds (tqdm): shown on a
terminal only, quiet when output is piped, captured or in CI."""

from __future__ import annotations

import os
import sys

__all__ = ["progress", "shows_progress"]


def shows_progress(enabled: bool | None = None) -> bool:
    """Whether to draw a bar: ``enabled`` when given, else when standard error is a
    terminal and the ``CI`` environment variable is not set."""
    if enabled is not None:
        return bool(enabled)
    if os.environ.get("CI"):
        return False
    stream = sys.stderr
    return bool(getattr(stream, "isatty", None) and stream.isatty())


#: The line of a bar without a total: ``diagnose: 3 fits [00:05, round 1: candidates]``.
#: tqdm's own adds the rate, which for slow steps it inverts to "1.61s/ fits" (the unit's
#: leading space is what separates it from the count).
UNCOUNTED_FORMAT = "{desc}: {n_fmt}{unit} [{elapsed}{postfix}]"


def progress(*, total: int | None, desc: str, unit: str = "it", enabled: bool | None = None):
    """A :class:`tqdm.tqdm` bar on standard error (a disabled one when
    :func:`shows_progress` says no); use as a context manager and call ``update()``.
    Without a ``total`` the line counts in ``unit`` (give it its leading space, ``" fits"``)
    and shows the elapsed time (:data:`UNCOUNTED_FORMAT`)."""
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=unit, disable=not shows_progress(enabled),
                leave=False, file=sys.stderr, dynamic_ncols=True,
                bar_format=UNCOUNTED_FORMAT if total is None else None)
