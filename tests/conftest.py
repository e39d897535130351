"""Test configuration: single-threaded BLAS/OpenMP, a private derivation cache, and the
independent reference models importable from ``tests/``."""

import os
import sys
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

_TESTS = Path(__file__).resolve().parent
# pytest has put tests/ on the path to import this file: its folders tests/estimate,
# tests/analogs, ... would be found as namespace packages before an editable install of
# the project, so the project's packages are imported with tests/ off the path
_path = sys.path[:]
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != _TESTS]
import analogs  # noqa: E402,F401
import derive  # noqa: E402,F401
import estimate  # noqa: E402,F401

sys.path[:] = _path
if str(_TESTS) not in sys.path:
    sys.path.insert(0, str(_TESTS))
# child processes (a Dask LocalCluster's workers) start from this path without the trick
# above: with the folder holding the project's packages on it, a regular package wins over
# the namespace portions in tests/ wherever they stand on the path
_PACKAGES = str(Path(estimate.__file__).resolve().parents[1])
if _PACKAGES not in sys.path:
    sys.path.append(_PACKAGES)

import pytest


@pytest.fixture(scope="session", autouse=True)
def _private_cache(tmp_path_factory):
    """Derived models are cached in a folder of this test session, not in the user's home,
    shared by the session's xdist workers: a model one worker is deriving (the spacecraft's
    takes 40 s) is waited for by the other (:func:`derive.cache.building`), not derived
    twice."""
    if "SLOSH_CACHE_DIR" not in os.environ or os.environ.get("SLOSH_TEST_KEEP_CACHE") != "1":
        root = tmp_path_factory.getbasetemp()
        if os.environ.get("PYTEST_XDIST_WORKER"):
            root = root.parent  # the session's folder, above each worker's own
        folder = root / "slosh-cache"
        folder.mkdir(mode=0o700, exist_ok=True)
        os.environ["SLOSH_CACHE_DIR"] = str(folder)
    yield


@pytest.fixture(autouse=True)
def _python_sigint():
    """Every test runs with Python's own SIGINT handler (KeyboardInterrupt), which child
    processes inherit as "not ignored". A test run started in the background of a
    non-interactive shell (``pytest &``, some CI runners) inherits SIGINT ignored; the
    tests that interrupt themselves or a child then failed, or not, depending on whether an
    earlier test in the same worker had put Python's handler back (a notebook's kernel
    client does)."""
    import signal

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)
