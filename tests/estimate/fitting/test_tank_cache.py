"""The tank modal analyses kept on disk: the same prediction as a fresh solve, read back
without solving, damaged entries and folders others can write to are never trusted."""

from __future__ import annotations

import dataclasses

import pytest

from analogs.tank import Exact, Ritz, Sphere, predict
from estimate.fitting._tank_cache import CachedSolver


@dataclasses.dataclass(frozen=True)
class Counting:
    """A solver that counts its solves (a list shared by its copies)."""

    inner: Ritz
    calls: list = dataclasses.field(default_factory=list, compare=False)

    @property
    def name(self):
        return self.inner.name

    def solve(self, tank, depth, n_modes):
        self.calls.append(depth)
        return self.inner.solve(tank, depth, n_modes)

    def __repr__(self):  # the cache key: the solver it wraps
        return f"Counting({self.inner!r})"


def _numbers(p):
    return ([(m.mass, m.length, m.hinge_height, m.frequency_hz, m.amplitude_ratio)
             for m in p.modes], p.fixed_mass)


def test_cached_prediction_equals_a_fresh_solve_and_is_read_back(tmp_path, monkeypatch):
    monkeypatch.setenv("SLOSH_CACHE_DIR", str(tmp_path))
    tank = Sphere(0.1016)
    fresh = predict(tank, fill=0.6, modes=2, method=Exact())
    solver = Counting(Ritz(degree=60))
    first = predict(tank, fill=0.6, modes=2, method=CachedSolver(solver))
    again = predict(tank, fill=0.6, modes=2, method=CachedSolver(solver))
    assert len(solver.calls) == 1  # the second came from disk
    assert _numbers(first) == _numbers(again) == _numbers(fresh)  # bit for bit (JSON floats)
    predict(tank, fill=0.61, modes=2, method=CachedSolver(solver))
    assert len(solver.calls) == 2  # another fill is another entry


def test_damaged_entries_are_solved_again(tmp_path, monkeypatch):
    monkeypatch.setenv("SLOSH_CACHE_DIR", str(tmp_path))
    solver = Counting(Ritz(degree=20))
    good = predict(Sphere(0.2), fill=0.4, method=CachedSolver(solver))
    (entry,) = (tmp_path / "tank").glob("*.json")
    text = entry.read_text()
    for damage in ("", text[: len(text) // 2], text.replace("[", "[1.5, ", 1), "[1, 2]"):
        entry.write_text(damage)
        again = predict(Sphere(0.2), fill=0.4, method=CachedSolver(solver))
        assert _numbers(again) == _numbers(good)
    assert len(solver.calls) == 5


def test_a_folder_others_can_write_to_is_not_used(tmp_path, monkeypatch):
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    monkeypatch.setenv("SLOSH_CACHE_DIR", str(shared))
    solver = Counting(Ritz(degree=20))
    from derive.cache import UntrustedCache

    with pytest.warns(UntrustedCache, match="writable by group or others"):
        for _ in range(2):
            predict(Sphere(0.2), fill=0.4, method=CachedSolver(solver))
    # kept in a private temporary folder for the process, not in the shared one
    assert len(solver.calls) == 1 and not (shared / "tank").exists()


def test_case_file_predictions_use_the_cache(tmp_path, monkeypatch):
    """``tank_prediction`` (case files, the fit's start values) goes through the cache and
    refuses an unknown method by name."""
    from analogs.errors import InputError
    from estimate.fitting.initial import tank_prediction

    monkeypatch.setenv("SLOSH_CACHE_DIR", str(tmp_path))
    kw = dict(density=998.2, viscosity=1.0e-6, gravity=9.81)
    p = tank_prediction(Sphere(0.1016), 0.6, **kw)
    assert len(list((tmp_path / "tank").glob("*.json"))) == 1
    assert _numbers(p) == _numbers(predict(Sphere(0.1016), fill=0.6, modes=1,
                                           liquid=p.liquid, gravity=9.81))
    with pytest.raises(InputError, match="method must be one of"):
        tank_prediction(Sphere(0.1016), 0.6, method="magic", **kw)
