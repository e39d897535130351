"""Placeholder."""
__all__ = ["Discrimination", "discrimination"]


class Discrimination:
    pass


def discrimination(*args, **kwargs):
    raise NotImplementedError
