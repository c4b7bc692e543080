"""Run untrusted work (expanding a stranger's xacro or SDF includes) in a child process with CPU, memory and time
limits.

The expression sandbox (:mod:`s2r.sources.urdf.xacro_sandbox`) stops a xacro from running code, but an allowed
expression or macro can still exhaust the machine: ``${10**10**10}`` computes a ten-billion-digit integer,
``${'x' * 10**10}`` asks for 10 GB, and a macro that calls itself twice per level doubles the document
thirty times. No syntax check bounds these, so the expansion runs in a forked child under ``RLIMIT_CPU``
and ``RLIMIT_AS``, with a wall-clock limit enforced by the parent; a child that overruns is killed and
the caller gets one :class:`~s2r.errors.SourceError` line that names the limit. SDF include expansion
(:mod:`s2r.sources.sdf.include`) runs the same way, with its own budget as the first bound.

Where ``os.fork`` does not exist (Windows) the work runs in-process, unlimited.
"""

from __future__ import annotations

import os
import pickle
import select
import signal
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

from s2r.errors import S2RError, SourceError

__all__ = ["Limits", "run_limited"]

T = TypeVar("T")


@dataclass(frozen=True)
class Limits:
    """Resource limits of one isolated run.

    Attributes:
        cpu_s: CPU seconds the child may use (``RLIMIT_CPU``; SIGXCPU ends it).
        memory_bytes: address space the child may add to what it inherits (``RLIMIT_AS``).
        wall_s: wall-clock seconds before the parent kills the child (a child blocked, not computing).
    """

    cpu_s: int = 10
    memory_bytes: int = 1 << 30
    wall_s: float = 120.0


def _address_space_bytes() -> int:
    """This process's current virtual size in bytes (0 when /proc is unavailable)."""
    try:
        pages = int(Path("/proc/self/statm").read_text(encoding="ascii").split()[0])
    except (OSError, ValueError, IndexError):
        return 0
    return pages * os.sysconf("SC_PAGE_SIZE")


def _set_child_limits(limits: Limits) -> None:
    import resource

    resource.setrlimit(resource.RLIMIT_CPU, (limits.cpu_s, limits.cpu_s + 5))
    inherited = _address_space_bytes()
    if inherited:
        soft, hard = resource.getrlimit(resource.RLIMIT_AS)
        wanted = inherited + limits.memory_bytes
        if hard != resource.RLIM_INFINITY:
            wanted = min(wanted, hard)
        if soft == resource.RLIM_INFINITY or wanted < soft:
            resource.setrlimit(resource.RLIMIT_AS, (wanted, hard))


def _child(write_fd: int, work: Callable[[], Any], limits: Limits) -> None:
    """Body of the forked child: never returns (``os._exit``), so no parent cleanup runs twice."""
    code = 0
    try:
        _set_child_limits(limits)
        try:
            payload = pickle.dumps(("ok", work()))
        except MemoryError:
            payload = pickle.dumps(("memory", None))
        except S2RError as exc:
            payload = pickle.dumps(("error", (type(exc).__name__, exc.message, exc.path, exc.field, exc.hint)))
        view = memoryview(payload)
        while view:
            view = view[os.write(write_fd, view):]
    except BaseException:  # the child must reach os._exit whatever happens
        code = 70
    finally:
        os._exit(code)


def _read_all(read_fd: int, pid: int, wall_s: float) -> bytes | None:
    """Everything the child writes, or None when the wall-clock limit passes first (the child is killed)."""
    chunks: list[bytes] = []
    deadline = time.monotonic() + wall_s
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            os.kill(pid, signal.SIGKILL)
            return None
        ready, _, _ = select.select([read_fd], [], [], min(left, 1.0))
        if ready:
            chunk = os.read(read_fd, 1 << 20)
            if not chunk:
                return b"".join(chunks)
            chunks.append(chunk)


_XACRO_HINT = "a runaway expression such as ${10**10**10} or a macro that expands itself without end; fix the file"


def run_limited(work: Callable[[], T], *, path: Path, what: str, limits: Limits, field: str = "xacro",
                hint: str = _XACRO_HINT) -> T:
    """Return ``work()`` computed in a child process under ``limits``.

    ``work`` must return a picklable value; an :class:`~s2r.errors.S2RError` it raises is raised again here
    (as a :class:`~s2r.errors.SourceError` with the same message, file, field and hint). ``field`` and ``hint``
    are those of the error raised when a limit is overrun (``what`` stopped: which limit).

    Raises:
        SourceError: the child overran a limit, died, or ``work`` raised an S2RError.
    """
    if not hasattr(os, "fork"):
        return work()
    read_fd, write_fd = os.pipe()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # 3.12+: fork of a threaded parent; child is pure Python
        pid = os.fork()
    if pid == 0:  # pragma: no cover - runs in the child, whose coverage is not collected
        os.close(read_fd)
        _child(write_fd, work, limits)
    os.close(write_fd)
    try:
        data = _read_all(read_fd, pid, limits.wall_s)
    finally:
        os.close(read_fd)
        _, status = os.waitpid(pid, 0)
    def stopped(reason: str) -> SourceError:
        return SourceError(f"{what} stopped: {reason}", path=path, field=field, hint=hint)

    if data is None:
        raise stopped(f"it took longer than {limits.wall_s:g} s")
    if os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGXCPU:
        raise stopped(f"it used more than {limits.cpu_s} s of CPU")
    if not data:
        raise stopped(f"the expanding process ended without a result (status {status})")
    kind, value = pickle.loads(data)  # our own child's bytes, through our own pipe
    if kind == "memory":
        raise stopped(f"it needed more than {limits.memory_bytes >> 20} MiB of memory")
    if kind == "error":
        _name, message, err_path, field, hint = value
        raise SourceError(message, path=err_path, field=field, hint=hint)
    return value  # type: ignore[no-any-return]
