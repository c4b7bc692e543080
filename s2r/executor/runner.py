"""The one executor seam for s2r's parallel work: local processes by default, Dask distributed on request.

:func:`open_runner` gives a :class:`TaskRunner` over either :func:`s2r.executor.local.local_pool` or a Dask
``distributed.Client`` (an existing scheduler at ``tcp://host:8786``, or a local cluster of worker processes
started for the run). ``distributed`` is imported only when Dask is asked for. Tasks must be module-level functions
with picklable arguments and results.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import as_completed as futures_completed
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from s2r.errors import S2RError
from s2r.executor.local import children_search_no_relative_folder, local_pool

__all__ = ["SCHEDULER_DEADLINE_S", "SchedulerLost", "TaskOutcome", "TaskRunner", "open_runner"]

ItemT = TypeVar("ItemT")
ResultT = TypeVar("ResultT")

#: How long a Dask scheduler may take to answer (s): connect and handshake together, a hard deadline.
SCHEDULER_DEADLINE_S = 6.0
_CLOSE_S = 5.0


@dataclass(frozen=True)
class TaskOutcome(Generic[ItemT, ResultT]):
    """One finished task: its input, its result, or the exception it raised (then ``result`` is None)."""

    index: int
    item: ItemT
    result: ResultT | None
    error: BaseException | None


class TaskRunner:
    """Runs ``fn(item)`` for many items on the chosen backend; outcomes arrive as tasks finish.

    A task that raises does not stop the others: its exception comes back in its :class:`TaskOutcome`. On Dask,
    a task whose worker dies is run again on another (the scheduler's own retry, up to
    ``distributed.scheduler.allowed-failures`` times); :attr:`lost_workers` names the workers that left during the
    run. Losing the scheduler itself raises :class:`SchedulerLost` within :data:`SCHEDULER_LOST_S`; leaving the
    loop early (an error, Ctrl-C) cancels every task not yet finished, on the cluster too.
    """

    def __init__(self, backend: Any, *, kind: str, workers: int, address: str = "") -> None:
        self._backend = backend
        self.kind = kind  # "local", "dask-local" or "dask"
        self.workers = workers
        self.address = address
        self.lost_workers: list[str] = []

    def as_completed(self, fn: Callable[[ItemT], ResultT], items: Sequence[ItemT]
                     ) -> Iterator[TaskOutcome[ItemT, ResultT]]:
        """Submit every item, then yield outcomes in completion order."""
        if self.kind == "local":
            futures = {self._backend.submit(fn, item): k for k, item in enumerate(items)}
            try:
                for future in futures_completed(futures):
                    yield _outcome(future, futures[future], items)
            finally:
                for future in futures:
                    future.cancel()
            return
        futures = {self._backend.submit(fn, item, pure=False): k for k, item in enumerate(items)}
        try:
            for future in _dask_completed(self._backend, list(futures), self):
                yield _outcome(future, futures[future], items)
        finally:
            with contextlib.suppress(Exception):  # the scheduler may be gone: nothing left to cancel there
                self._backend.cancel(list(futures), force=True)


def _outcome(future: Any, k: int, items: Sequence[Any]) -> TaskOutcome[Any, Any]:
    try:
        return TaskOutcome(k, items[k], future.result(), None)
    except Exception as exc:  # a task's own failure is data for the caller, not the end of the run
        return TaskOutcome(k, items[k], None, exc)


class SchedulerLost(S2RError):
    """The Dask scheduler went away in the middle of a run (its tasks' results cannot come back)."""


#: How long a Dask client may stay cut off from its scheduler, or a cluster stay without any worker, mid-run before
#: the run is given up (s).
SCHEDULER_LOST_S = 10.0
NO_WORKERS_S = 30.0
_POLL_S = 0.2


class _ClusterWatch:
    """What the scheduler says about its workers during a run, pushed to the client as events (no polling):
    the workers that left unexpectedly, and how many remain."""

    def __init__(self, client: Any) -> None:
        self.lost: list[str] = []
        self.workers = len(_worker_names(client))
        self._client = client
        client.subscribe_topic("all", self._event)

    def _event(self, event: tuple[float, Any]) -> None:
        message = event[1] if isinstance(event, tuple) and len(event) == 2 else {}
        if not isinstance(message, dict):
            return
        if message.get("action") == "add-worker":
            self.workers += 1
        elif message.get("action") == "remove-worker":
            self.workers = max(0, self.workers - 1)
            if not message.get("expected"):
                self.lost.append(str(message.get("worker", "?")))

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self._client.unsubscribe_topic("all")


def _worker_names(client: Any) -> set[str]:
    """The addresses of the scheduler's workers now (one round trip; empty when it cannot answer)."""
    with contextlib.suppress(Exception):
        return set((client.scheduler_info() or {}).get("workers", {}))
    return set()


def _given_up(runner: TaskRunner, why: str, done: int, total: int) -> SchedulerLost:
    return SchedulerLost(f"{why} mid-run ({done} of {total} tasks finished); nothing was written",
                         path=runner.address or None, field="--scheduler",
                         hint="restart the scheduler and its workers, then run again with --resume")


def _dask_completed(client: Any, futures: list[Any], runner: TaskRunner) -> Iterator[Any]:
    """``futures`` as they finish, watching the cluster: the workers lost go to ``runner.lost_workers``; a
    scheduler unreachable for :data:`SCHEDULER_LOST_S`, or no worker for :data:`NO_WORKERS_S`, raises
    :class:`SchedulerLost` (never a hang)."""
    from distributed import as_completed as dask_completed

    pending: Any = dask_completed(futures)  # type: ignore[no-untyped-call]
    watch = _ClusterWatch(client)
    since = {"cut off": None, "no workers": None}  # type: dict[str, float | None]
    limits = {"cut off": SCHEDULER_LOST_S, "no workers": NO_WORKERS_S}
    why = {"cut off": "lost the Dask scheduler", "no workers": "no Dask worker left"}
    done = 0
    try:
        while not pending.is_empty():
            batch = pending.next_batch(block=False)
            now = time.monotonic()
            for key, bad in (("cut off", client.status != "running"), ("no workers", watch.workers < 1)):
                start = since[key]
                if not bad:
                    since[key] = None
                elif start is None:
                    since[key] = now
                elif now - start > limits[key]:
                    raise _given_up(runner, why[key], done, len(futures))
            runner.lost_workers = list(watch.lost)
            for future in batch:
                if future.status == "cancelled":  # the client cancels every task when its scheduler goes
                    raise _given_up(runner, "lost the Dask scheduler" if client.status != "running" else
                                    "the run's tasks were cancelled on the cluster", done, len(futures))
                done += 1
                yield future
            if not batch:
                time.sleep(_POLL_S)
        runner.lost_workers = list(watch.lost)
    finally:
        watch.close()


@contextlib.contextmanager
def open_runner(*, workers: int, scheduler: str | None = None, dask: bool = False) -> Iterator[TaskRunner]:
    """A :class:`TaskRunner` for the run, shut down on exit.

    Args:
        workers: worker processes of a local pool or of a local Dask cluster (ignored with ``scheduler``).
        scheduler: address of a running Dask scheduler (``tcp://host:8786``); implies Dask.
        dask: use Dask even without a scheduler: a ``LocalCluster`` of ``workers`` single-threaded processes.
    """
    if workers < 1:
        raise S2RError(f"must be at least 1, got {workers}", field="--workers", hint="e.g. 2")
    if scheduler is None and not dask:
        with local_pool(workers) as pool:
            yield TaskRunner(pool, kind="local", workers=workers)
        return
    with children_search_no_relative_folder(), _quiet_dask():  # nannies spawn (and respawn) the local workers
        client, cluster = _dask_client(workers=workers, scheduler=scheduler)
        try:
            yield TaskRunner(client, kind="dask" if scheduler else "dask-local", workers=workers,
                             address=scheduler or "")
        finally:
            with contextlib.suppress(Exception):  # a lost scheduler must not hold the exit
                client.close(timeout=_CLOSE_S)
            if cluster is not None:
                cluster.close()


@contextlib.contextmanager
def _quiet_dask() -> Iterator[None]:
    """Dask's own log records (a lost scheduler or worker prints tracebacks) held below CRITICAL while a run is
    open: s2r reports what happened itself, in one line."""
    import logging

    with contextlib.suppress(ImportError):  # its loggers exist once it is imported
        import distributed  # noqa: F401
    loggers = [logging.getLogger(name) for name in ["distributed", *logging.root.manager.loggerDict]
               if name.split(".")[0] == "distributed"]
    levels = [logger.level for logger in loggers]
    for logger in loggers:
        logger.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for logger, level in zip(loggers, levels, strict=True):
            logger.setLevel(level)


def _dask_client(*, workers: int, scheduler: str | None) -> tuple[Any, Any]:
    """``(Client, LocalCluster or None)``; S2RError naming --scheduler when it cannot be reached."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise S2RError("Dask's distributed is not installed", field="--scheduler",
                       hint="pip install 'distributed' (make installs it)") from None
    if scheduler is not None:
        return _connect(Client, scheduler), None
    try:
        cluster = _local_cluster(LocalCluster, workers)
    except Exception as exc:  # e.g. a script without a main guard, whose spawned workers cannot start
        raise S2RError(f"could not start a local Dask cluster of {workers} workers: {type(exc).__name__}: "
                       f"{' '.join(str(exc).split())[:200]}", field="--workers",
                       hint="fewer --workers, or a running scheduler with --scheduler; a script calling s2r needs "
                       "an `if __name__ == \"__main__\":` guard") from None
    return Client(cluster), cluster  # type: ignore[no-untyped-call]


def _local_cluster(cluster_type: Any, workers: int) -> Any:
    """Dask's LocalCluster of ``workers`` single-threaded processes, every socket on loopback, no dashboard."""
    return cluster_type(  # type: ignore[no-untyped-call]
        n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None,
        silence_logs=40, scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})  # its http server: loopback


def _unreachable(scheduler: str, why: str) -> S2RError:
    return S2RError(f"cannot reach the Dask scheduler: {' '.join(why.split())[:200]}", path=scheduler,
                    field="--scheduler", hint="give tcp://HOST:PORT of a running scheduler (dask scheduler), or drop "
                    "--scheduler for a local cluster")


def _connect(client_type: Any, scheduler: str) -> Any:
    """A ``Client`` of ``scheduler`` within :data:`SCHEDULER_DEADLINE_S`, else S2RError naming --scheduler.

    Dask's own connect timeout does not cover the handshake (a port that accepts and never answers holds it for
    ``distributed.comm.timeouts.tcp``, 30 s), nor garbage answers: the connect runs in a daemon thread that is
    abandoned (its client closed if it ever connects) at the deadline, and any failure is named as one line.
    """
    from distributed.comm.addressing import parse_address
    from distributed.comm.registry import get_backend

    try:
        get_backend(parse_address(scheduler, strict=True)[0])
    except ValueError as exc:
        raise _unreachable(scheduler, f"not an address ({exc})") from None
    outcome: dict[str, Any] = {}
    lock = threading.Lock()

    def connect() -> None:
        try:
            client = client_type(scheduler, timeout=f"{SCHEDULER_DEADLINE_S}s")
        except BaseException as exc:  # any failure (even a MemoryError from a garbage answer) is data
            outcome["error"] = exc
            return
        with lock:
            abandoned = outcome.setdefault("client", client) is not client  # the caller gave up already
        if abandoned:
            with contextlib.suppress(Exception):
                client.close()

    thread = threading.Thread(target=connect, name="s2r-dask-connect", daemon=True)
    thread.start()
    thread.join(SCHEDULER_DEADLINE_S)
    with lock:
        client = outcome.setdefault("client", None)
    if client is not None:
        return client
    error = outcome.get("error")
    if error is None:
        raise _unreachable(scheduler, f"no answer within {SCHEDULER_DEADLINE_S:g} s")
    raise _unreachable(scheduler, f"{type(error).__name__}: {error}")
