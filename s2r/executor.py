"""The one executor seam for s2r's parallel work: local processes by default, Dask distributed on request.

Every stage that runs work in parallel (corner detection, validate's renders, fleet checks) takes its pool
from here, so a new backend is added once:

- :func:`local_pool`: a ``concurrent.futures.ProcessPoolExecutor`` whose workers start by ``fork`` where it
  exists (instant, cv2 already loaded, the caller's ``__main__`` never re-imported) and die with their parent,
  even when the parent is killed with ``kill -9``;
- :func:`open_runner`: a :class:`TaskRunner` over either that pool or a Dask ``distributed.Client`` (an
  existing scheduler at ``tcp://host:8786``, or a local cluster of worker processes started for the run).
  ``distributed`` is imported only when Dask is asked for.

Tasks must be module-level functions with picklable arguments and results.

Programs s2r starts (a spawned Dask worker, the MuJoCo probe) get :func:`child_environment`: ``import cv2``
leaves LD_LIBRARY_PATH ending in an empty entry, which the dynamic loader reads as the current folder.
"""

from __future__ import annotations

import contextlib
import ctypes
import multiprocessing as mp
import os
import re
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures import as_completed as futures_completed
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from s2r.errors import S2RError

__all__ = ["TaskOutcome", "TaskRunner", "child_environment", "children_search_no_relative_folder", "local_pool",
           "open_runner"]

ItemT = TypeVar("ItemT")
ResultT = TypeVar("ResultT")

_PR_SET_PDEATHSIG = 1  # linux/prctl.h
_WATCHDOG_PERIOD_S = 1.0
#: How long a Dask scheduler may take to answer (s): connect and handshake together, a hard deadline.
SCHEDULER_DEADLINE_S = 6.0


def _die_with_parent(parent_pid: int) -> None:
    """Pool initializer: end this worker when the parent process dies, even by ``kill -9``.

    On Linux the kernel sends SIGKILL when the parent goes (``prctl(PR_SET_PDEATHSIG)``); everywhere a daemon
    thread also watches the parent pid once a second and exits when the worker was re-parented.
    """
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent_pid:  # the parent died before the line above took effect
        os._exit(1)

    def watch() -> None:
        while True:
            time.sleep(_WATCHDOG_PERIOD_S)
            if os.getppid() != parent_pid:
                os._exit(1)

    threading.Thread(target=watch, name="s2r-parent-watchdog", daemon=True).start()


def child_environment(env: Mapping[str, str] | None = None) -> dict[str, str]:
    """``env`` (default ``os.environ``) for a program s2r starts, with only the LD_LIBRARY_PATH entries that do
    not depend on the current folder: absolute paths and ``$ORIGIN`` ones (the executable's folder); the variable
    is dropped when none is left.

    ``import cv2`` (opencv-python) sets LD_LIBRARY_PATH to its own folder followed by the old value, and leaves a
    trailing empty entry when there was none. The dynamic loader reads an empty or relative entry against the
    current folder, so every child would first look there for its libraries (``libpython3.11.so.1.0``,
    ``libc.so.6``, ...): a library planted in the folder s2r runs from would run inside the child. glibc splits
    the variable at ``;`` as well as ``:``, so both separate entries here."""
    out = dict(os.environ if env is None else env)
    value = out.get("LD_LIBRARY_PATH")
    if value is not None:
        kept = [entry for entry in re.split(r"[:;]", value)
                if entry.startswith(("/", "$ORIGIN", "${ORIGIN}"))]
        if kept:
            out["LD_LIBRARY_PATH"] = ":".join(kept)
        else:
            del out["LD_LIBRARY_PATH"]
    return out


@contextlib.contextmanager
def children_search_no_relative_folder() -> Iterator[None]:
    """While open, ``os.environ``'s LD_LIBRARY_PATH is :func:`child_environment`'s, for children started by
    code that takes no environment (multiprocessing's spawn, Dask's nannies); restored on exit."""
    before = os.environ.get("LD_LIBRARY_PATH")
    clean = child_environment().get("LD_LIBRARY_PATH")
    _set_library_path(clean)
    try:
        yield
    finally:
        _set_library_path(before)


def _set_library_path(value: str | None) -> None:
    if value is None:
        os.environ.pop("LD_LIBRARY_PATH", None)
    else:
        os.environ["LD_LIBRARY_PATH"] = value


def local_pool(jobs: int) -> ProcessPoolExecutor:
    """A process pool of ``jobs`` workers that die with this process.

    fork: workers start instantly with cv2 loaded and never re-import the caller's ``__main__`` (scripts
    without a main guard keep working); spawn where fork does not exist. Never call ``cv2.setNumThreads`` in a
    forked child: it waits for the parent's pool threads, which do not exist there, and hangs.
    """
    if jobs < 1:
        raise S2RError(f"must be at least 1, got {jobs}", field="jobs", hint="e.g. 2")
    ctx = mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn")
    return ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=_die_with_parent,
                               initargs=(os.getpid(),))


@dataclass(frozen=True)
class TaskOutcome(Generic[ItemT, ResultT]):
    """One finished task: its input, its result, or the exception it raised (then ``result`` is None)."""

    index: int
    item: ItemT
    result: ResultT | None
    error: BaseException | None


class TaskRunner:
    """Runs ``fn(item)`` for many items on the chosen backend; outcomes arrive as tasks finish.

    A task that raises does not stop the others: its exception comes back in its :class:`TaskOutcome`.
    """

    def __init__(self, backend: Any, *, kind: str, workers: int) -> None:
        self._backend = backend
        self.kind = kind  # "local", "dask-local" or "dask"
        self.workers = workers

    def as_completed(self, fn: Callable[[ItemT], ResultT], items: Sequence[ItemT]
                     ) -> Iterator[TaskOutcome[ItemT, ResultT]]:
        """Submit every item, then yield outcomes in completion order."""
        if self.kind == "local":
            futures = {self._backend.submit(fn, item): k for k, item in enumerate(items)}
            done: Iterator[Any] = futures_completed(futures)
        else:
            from distributed import as_completed as dask_completed

            futures = {self._backend.submit(fn, item, pure=False): k for k, item in enumerate(items)}
            done = iter(dask_completed(list(futures)))  # type: ignore[no-untyped-call]
        for future in done:
            k = futures[future]
            try:
                yield TaskOutcome(k, items[k], future.result(), None)
            except Exception as exc:  # a task's own failure is data for the caller, not the end of the run
                yield TaskOutcome(k, items[k], None, exc)


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
    with children_search_no_relative_folder():  # a local cluster's nannies spawn (and respawn) its workers
        client, cluster = _dask_client(workers=workers, scheduler=scheduler)
        try:
            yield TaskRunner(client, kind="dask" if scheduler else "dask-local", workers=workers)
        finally:
            client.close()
            if cluster is not None:
                cluster.close()


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
