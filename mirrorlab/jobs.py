"""One executor for independent jobs: lab submissions to grade, frames of a batch render,
cells of an accuracy sweep. A job is a module-level function and its arguments, named by
a key; results come back as each job finishes, each key exactly once.

Engines (:func:`open_executor`):

- ``serial``: in this process, one after another (``jobs`` = 1 and no scheduler).
- ``pool``: a local :class:`concurrent.futures.ProcessPoolExecutor` of ``jobs`` processes,
  kept from the first run to :meth:`Executor.close`. When a worker process dies, the pool
  breaks; the jobs that had not finished are submitted again to a new pool (up to
  ``retries`` times each).
- ``dask``: a Dask distributed cluster: a :class:`distributed.LocalCluster` of ``jobs``
  worker processes (one thread each), or the running scheduler at ``scheduler``
  (``tcp://host:8786``). When a worker dies, the scheduler runs its jobs again on another
  worker. Workers need mirrorlab installed (and, for files, the same paths). Dask is an
  optional dependency (``pip install 'mirrorlab[dask]'``); see :func:`require_dask`.

A job that raises gives its key and the error message instead of a result; the executor
never drops a key and never yields one twice.
"""

from __future__ import annotations

import concurrent.futures
import uuid
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any, Self

from mirrorlab.errors import MissingExtraError

RETRIES = 2
CONNECT_TIMEOUT = "20s"
"""How long a Dask client tries to reach a ``--scheduler`` before giving up."""


@dataclass(frozen=True)
class Outcome:
    """One job's end: its ``key`` and either ``value`` or ``error`` (one line)."""

    key: str
    value: Any = None
    error: str | None = None


def _describe(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}".splitlines()[0][:300]


class Executor:
    """Runs jobs; use as a context manager. :meth:`run` yields an :class:`Outcome` per key
    as the jobs finish."""

    engine = "serial"
    workers = 1

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        pass

    def run(self, function: Callable[..., Any], jobs: Mapping[str, tuple]) -> Iterator[Outcome]:
        for key, args in jobs.items():
            try:
                yield Outcome(key, function(*args))
            except Exception as exc:
                yield Outcome(key, error=_describe(exc))


class PoolExecutor(Executor):
    """``jobs`` local worker processes; jobs of a broken pool are re-run on a new one.

    The pool is made at the first :meth:`run` and kept for the later ones until
    :meth:`close`: its workers are forked once, from the process as it was then (the
    accuracy sweep forks them before it opens its own OpenGL context, and finds them idle
    while it times frames)."""

    engine = "pool"

    def __init__(self, workers: int, retries: int = RETRIES) -> None:
        self.workers = workers
        self.retries = retries
        self._pool: concurrent.futures.ProcessPoolExecutor | None = None

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def run(self, function: Callable[..., Any], jobs: Mapping[str, tuple]) -> Iterator[Outcome]:
        pending = dict(jobs)
        attempts = dict.fromkeys(jobs, 0)
        while pending:
            broken = False
            if self._pool is None:
                self._pool = concurrent.futures.ProcessPoolExecutor(self.workers)
            futures = {self._pool.submit(function, *args): key for key, args in pending.items()}
            try:
                for future in concurrent.futures.as_completed(futures):
                    key = futures[future]
                    try:
                        value = future.result()
                    except concurrent.futures.process.BrokenProcessPool:
                        broken = True
                        continue
                    except Exception as exc:
                        del pending[key]
                        yield Outcome(key, error=_describe(exc))
                        continue
                    del pending[key]
                    yield Outcome(key, value)
            finally:
                for future in futures:  # the caller stopped early: drop what has not begun
                    future.cancel()
            if not broken:
                break
            self.close()
            for key in list(pending):
                attempts[key] += 1
                if attempts[key] > self.retries:
                    del pending[key]
                    yield Outcome(key, error=f"its worker process died {attempts[key]} times")


def require_dask(option: str = "the dask engine") -> None:
    """:class:`~mirrorlab.errors.MissingExtraError` naming ``option`` (``--scheduler``,
    ``--engine dask``) and the extra to install when Dask distributed cannot be
    imported."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise MissingExtraError(option, "Dask (dask[distributed])", "dask") from None


class DaskExecutor(Executor):
    """Jobs as tasks of a Dask distributed cluster: a local one of ``workers`` processes, or
    the scheduler at ``address``."""

    engine = "dask"

    def __init__(
        self,
        workers: int = 2,
        address: str | None = None,
        retries: int = RETRIES,
        connect_timeout: str | None = None,
    ) -> None:
        require_dask("--scheduler" if address is not None else "--engine dask")
        from distributed import Client, LocalCluster

        self.retries = retries
        self.cluster = None
        if address is None:
            # ":0": any free port for the scheduler's HTTP routes (8787 may be taken)
            self.cluster = LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0"
            )
            self.client = Client(self.cluster)
        else:
            try:
                self.client = Client(address, timeout=connect_timeout or CONNECT_TIMEOUT)
            except OSError as exc:
                raise ValueError(
                    f"--scheduler: cannot reach a Dask scheduler at {address!r} ({exc})"
                ) from None
        self.workers = len(self.client.scheduler_info().get("workers", {})) or workers

    def close(self) -> None:
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()

    def run(self, function: Callable[..., Any], jobs: Mapping[str, tuple]) -> Iterator[Outcome]:
        from distributed import as_completed

        batch = uuid.uuid4().hex[:8]
        futures = {
            self.client.submit(
                function, *args, key=f"{key}-{batch}", pure=False, retries=self.retries
            ): key
            for key, args in jobs.items()
        }
        for future in as_completed(futures):
            key = futures[future]
            try:
                yield Outcome(key, future.result())
            except Exception as exc:
                yield Outcome(key, error=_describe(exc))
            finally:
                future.release()


def open_executor(jobs: int = 1, scheduler: str | None = None, engine: str = "pool") -> Executor:
    """The executor for ``jobs`` parallel jobs: a Dask client when ``scheduler`` is given;
    otherwise in this process for one job, else a process pool (``engine`` "pool", the
    default) or a local Dask cluster ("dask")."""
    if scheduler:
        return DaskExecutor(jobs, scheduler)
    if jobs <= 1:
        return Executor()
    if engine == "pool":
        return PoolExecutor(jobs)
    if engine != "dask":
        raise ValueError(f"--engine: expected dask or pool, got {engine!r}")
    return DaskExecutor(jobs)
