"""Local worker processes: how many cores this process may use, and pools whose workers die with it.

- :func:`local_pool`: a ``concurrent.futures.ProcessPoolExecutor`` whose workers start by ``fork`` where it exists
  (instant, cv2 already loaded, the caller's ``__main__`` never re-imported), all before it is returned, with
  SIGINT and SIGTERM blocked meanwhile (a signal then is the parent's alone); they die with their parent, even
  when it is killed with ``kill -9``. :func:`s2r.cvpool.opencv_pool` wraps it for OpenCV work.
- :func:`usable_cores`: the default worker count (the affinity mask and a cgroup CPU quota, not the host's cores).
- Programs s2r starts (a spawned Dask worker, the MuJoCo probe) get :func:`child_environment`: ``import cv2``
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
from collections.abc import Iterator, Mapping
from concurrent.futures import ProcessPoolExecutor

from s2r.errors import S2RError

__all__ = ["WorkersUnavailable", "child_environment", "children_search_no_relative_folder", "local_pool",
           "usable_cores"]

_PR_SET_PDEATHSIG = 1  # linux/prctl.h
_WATCHDOG_PERIOD_S = 1.0
_START_SIGNALS = {signal.SIGINT, signal.SIGTERM}


class WorkersUnavailable(S2RError):
    """Worker processes cannot be started here (no writable ``/dev/shm`` for multiprocessing's semaphores)."""


def usable_cores() -> int:
    """The CPUs this process may run on: its affinity mask (``taskset``, a container's cpuset) and a cgroup v2 CPU
    quota (``cpu.max``, e.g. ``docker --cpus 2``), whichever is smaller; at least 1. ``os.cpu_count()`` counts the
    whole host, so a limited container would start a worker per host core."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    with contextlib.suppress(OSError, ValueError):
        with open("/sys/fs/cgroup/cpu.max", encoding="ascii") as f:
            quota, period = f.read().split()[:2]
        if quota != "max":
            cores = min(cores, max(1, -(-int(quota) // int(period))))
    return max(1, cores)


def _die_with_parent(parent_pid: int) -> None:
    """Pool initializer: end this worker when the parent process dies, even by ``kill -9``; leave Ctrl-C to the
    parent.

    On Linux the kernel sends SIGKILL when the parent goes (``prctl(PR_SET_PDEATHSIG)``); everywhere a daemon
    thread also watches the parent pid once a second and exits when the worker was re-parented. The worker was
    forked with SIGINT and SIGTERM blocked (:func:`local_pool`): a Ctrl-C that reached the process group while it
    started is discarded here (ignored while unblocked: it is the parent's to act on), so it never raises inside
    multiprocessing's start-up; then the inherited handlers are back, and a later Ctrl-C ends a running task at
    once, as before.
    """
    handlers = {sig: signal.getsignal(sig) for sig in _START_SIGNALS}
    for sig in _START_SIGNALS:
        signal.signal(sig, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, _START_SIGNALS)  # pending ones are dropped while ignored
    for sig, handler in handlers.items():
        signal.signal(sig, handler)
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
    """A process pool of ``jobs`` workers that die with this process, all started before it is returned.

    fork: workers start instantly with cv2 loaded and never re-import the caller's ``__main__`` (scripts
    without a main guard keep working); spawn where fork does not exist. Never call ``cv2.setNumThreads`` in a
    forked child: it waits for the parent's pool threads, which do not exist there, and hangs.
    """
    if jobs < 1:
        raise S2RError(f"must be at least 1, got {jobs}", field="jobs", hint="e.g. 2")
    ctx = mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn")
    try:
        pool = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=_die_with_parent,
                                   initargs=(os.getpid(),))
    except OSError as exc:  # the pool's queues need POSIX semaphores: a read-only or missing /dev/shm
        raise WorkersUnavailable(f"cannot start worker processes: {exc.strerror or exc} (multiprocessing needs a "
                                 "writable /dev/shm)", field="--jobs", hint="run with --jobs 1") from None
    _start_workers(pool)
    return pool


def _start_workers(pool: ProcessPoolExecutor) -> None:
    """Fork every worker of ``pool`` now, from this thread, with SIGINT and SIGTERM blocked until they are up.

    A Ctrl-C reaching the process group while the workers start would otherwise raise inside multiprocessing's
    start-up (a worker's traceback, a broken pool, an exit 0 after the signal was lost). Blocked, it is delivered
    here once every worker runs (:func:`_die_with_parent` unblocks them in the workers), and this process then
    shuts the pool down as after any interrupt."""
    blocking = hasattr(signal, "pthread_sigmask")
    old = signal.pthread_sigmask(signal.SIG_BLOCK, _START_SIGNALS) if blocking else set()
    try:
        pool.submit(os.getpid).result()  # with fork, the first task starts every worker
    except BaseException:
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    finally:
        if blocking:
            try:
                signal.pthread_sigmask(signal.SIG_SETMASK, old)  # a signal that came meanwhile is raised here
            except BaseException:
                pool.shutdown(wait=False, cancel_futures=True)
                raise
