"""The installed version of slosh-analogs (``slosh --version``, the fit record's provenance,
the campaign store's keys), read without importing anything heavy."""

from __future__ import annotations

__all__ = ["package_version"]


def package_version() -> str:
    """The installed version of slosh-analogs (``"unknown"`` when not installed).

    Examples
    --------
    >>> package_version()            # doctest: +SKIP
    '0.1.0'
    """
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("slosh-analogs")
    except PackageNotFoundError:  # pragma: no cover - running from an uninstalled checkout
        return "unknown"
