"""Executors that run independent tasks (Monte Carlo batches, batch fits): in this process,
or on Dask - an embedded local cluster by default, or an existing cluster by address.

Results come back in task order whichever executor runs them, so a computation whose tasks
are deterministic gives identical results everywhere.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any

from analogs.errors import InputError, MissingDependency

__all__ = ["DaskExecutor", "Executor", "LocalExecutor", "chunks", "executor_for"]


class Executor:
    """Runs ``fn(item, shared=shared)`` for each of ``items`` and returns the results in
    order; ``shared`` (large data all tasks need) is sent to each worker once."""

    def map(self, fn: Callable[[Any, Any], Any], items: Sequence[Any], shared: Any = None,
            *, done: Callable[[], None] | None = None) -> list[Any]:
        """``[fn(item, shared=shared) for item in items]``, in order; ``done()`` is called
        (in this process) as each task finishes, for progress bars."""
        raise NotImplementedError

    def as_completed(self, fn: Callable[[Any, Any], Any], items: Sequence[Any],
                     shared: Any = None) -> Iterator[tuple[int, Any]]:
        """Run ``fn(item, shared=shared)`` for each of ``items``; yield ``(index, future)`` as
        each task ends, in the order they end. ``future.result()`` returns the task's value
        or raises its exception. Closing the iterator early (``break``, an interrupt)
        cancels the tasks that have not started."""
        from concurrent.futures import Future

        for i, item in enumerate(items):
            future: Future = Future()
            try:
                future.set_result(fn(item, shared=shared))
            except Exception as err:
                future.set_exception(err)
            yield i, future

    def close(self) -> None:
        """Release workers the executor started (nothing for the local executor)."""

    def __enter__(self) -> "Executor":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def workers(self) -> int:
        """Number of workers the tasks are spread over."""
        return 1


class LocalExecutor(Executor):
    """Runs the tasks in this process on ``threads`` threads (default: the CPU count).

    CasADi releases the GIL while a function runs, so batches of compiled simulations run
    in parallel (1.6x on 2 cores). Results come back in task order, whatever the threads.
    """

    def __init__(self, threads: int | None = None) -> None:
        self.threads = max(1, int(threads if threads is not None else (os.cpu_count() or 1)))

    def map(self, fn: Callable[[Any, Any], Any], items: Sequence[Any], shared: Any = None,
            *, done: Callable[[], None] | None = None) -> list[Any]:
        def one(item):
            out = fn(item, shared=shared)
            if done is not None:
                done()
            return out

        if self.threads == 1 or len(items) < 2:
            return [one(item) for item in items]
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(self.threads) as pool:
            return list(pool.map(one, items))

    def as_completed(self, fn: Callable[[Any, Any], Any], items: Sequence[Any],
                     shared: Any = None) -> Iterator[tuple[int, Any]]:
        # always on worker threads, even one: the calling thread only waits, so an
        # interrupt reaches it there and never lands inside a task
        from concurrent.futures import ThreadPoolExecutor
        from concurrent.futures import as_completed as completed

        pool = ThreadPoolExecutor(self.threads)
        try:
            futures = {pool.submit(fn, item, shared=shared): i for i, item in enumerate(items)}
            for future in completed(futures):
                yield futures[future], future
        finally:
            pool.shutdown(wait=False, cancel_futures=True)

    @property
    def workers(self) -> int:
        return self.threads

    def __repr__(self) -> str:
        return f"LocalExecutor(threads={self.threads})"


def _import_distributed():
    try:
        import distributed
    except ImportError as err:  # pragma: no cover - depends on the environment
        raise MissingDependency("the Dask executor needs dask.distributed: "
                                "`python3 -m pip install '.[dask]'` (from a checkout) or "
                                "`python3 -m pip install 'slosh-analogs[dask]'`") from err
    return distributed


class DaskExecutor(Executor):
    """Runs the tasks on a Dask cluster.

    Parameters
    ----------
    address : str, optional
        Scheduler of an existing cluster, e.g. ``"tcp://host:8786"``. Default: start an
        embedded ``LocalCluster`` (processes, one thread each; closed by :meth:`close`).
    n_workers : int, optional
        Workers of the embedded cluster (default: the CPU count).
    client : distributed.Client, optional
        Use this client instead (it is not closed by :meth:`close`).

    Workers inherit ``SLOSH_CACHE_DIR`` (derived models and compiled code are shared
    through the disk cache on one machine; on a remote cluster each worker compiles once).
    """

    def __init__(self, address: str | None = None, *, n_workers: int | None = None,
                 client: Any = None) -> None:
        if address is not None and client is not None:
            raise InputError("pass either `address` or `client`, not both")
        distributed = _import_distributed()
        self._own = client is None
        self._cluster = None
        if client is not None:
            self.client = client
        elif address is not None:
            self.client = _connect(distributed, address)
        else:
            self._cluster = distributed.LocalCluster(
                n_workers=n_workers or os.cpu_count() or 1, threads_per_worker=1,
                processes=True, dashboard_address=None)
            self.client = distributed.Client(self._cluster)

    @property
    def workers(self) -> int:
        return max(1, len(self.client.scheduler_info().get("workers", {})))

    def map(self, fn: Callable[[Any, Any], Any], items: Sequence[Any], shared: Any = None,
            *, done: Callable[[], None] | None = None) -> list[Any]:
        data = self.client.scatter(shared, broadcast=True) if shared is not None else None
        futures = self.client.map(fn, list(items), shared=data, pure=False)
        if done is not None:
            for _ in _import_distributed().as_completed(futures):
                done()
        return self.client.gather(futures)

    def as_completed(self, fn: Callable[[Any, Any], Any], items: Sequence[Any],
                     shared: Any = None) -> Iterator[tuple[int, Any]]:
        distributed = _import_distributed()
        data = self.client.scatter(shared, broadcast=True) if shared is not None else None
        futures = self.client.map(fn, list(items), shared=data, pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        try:
            for future in distributed.as_completed(futures):
                yield index[future.key], future
        finally:
            self.client.cancel([f for f in futures if not f.done()])

    def close(self) -> None:
        if self._own:
            self.client.close()
            if self._cluster is not None:
                self._cluster.close()

    def __repr__(self) -> str:
        return f"DaskExecutor({self.client.scheduler.address!r})"


def _connect(distributed, address: str):
    """A client of the scheduler at ``address``; a malformed or unreachable address is an
    :class:`InputError` naming it (``--scheduler`` on the command line)."""
    where = f"--scheduler {address!r}"
    if not isinstance(address, str) or "://" not in address:
        raise InputError(f"{where}: expected a scheduler address such as tcp://127.0.0.1:8786")
    try:
        return distributed.Client(address)
    except (ValueError, TypeError) as err:  # a port that is not a number, an unknown protocol
        raise InputError(f"{where}: not a scheduler address ({err}); expected one such as "
                         "tcp://127.0.0.1:8786") from None
    except (OSError, TimeoutError) as err:
        raise InputError(f"{where}: no scheduler answers ({err}); start one with `dask "
                         "scheduler` (and workers with `dask worker ADDRESS`)") from None


def executor_for(scheduler: str | None = None, *, local: bool = False,
                 n_workers: int | None = None) -> Executor:
    """The executor of a command line: ``local=True`` runs in-process; otherwise Dask at
    ``scheduler`` (``"tcp://host:8786"``) or an embedded local cluster."""
    if local:
        if scheduler is not None:
            raise InputError("`--scheduler` and `--local` exclude each other")
        return LocalExecutor()
    return DaskExecutor(scheduler, n_workers=n_workers)


def chunks(n: int, size: int) -> Iterable[tuple[int, int]]:
    """``(start, stop)`` ranges of at most ``size`` covering ``range(n)``."""
    for start in range(0, n, size):
        yield start, min(n, start + size)

