"""Process-wide settings for the command line, made before numpy loads (:mod:`s2r.cli` imports this first).

- **One BLAS thread.** s2r runs its parallel work in worker processes (``--jobs``); the matrices it
  multiplies are small (a joint calibration's normal equations are about 22 x 4000), where OpenBLAS's extra
  threads mostly spin waiting for work: about 8 % of a 40-pair calibration's CPU time on 2 cores, and they
  compete with the workers for the cores. A value the user set (``OPENBLAS_NUM_THREADS``) is kept.
- **No pydantic plugin scan.** The first pydantic model built looks for plugins among every installed
  distribution's entry points (``importlib.metadata``): about 10 ms of every command's start-up, for plugins
  s2r's command line has no use for. ``PYDANTIC_DISABLE_PLUGINS=__all__`` unless the user set it.
- **glibc malloc keeps freed memory for reuse.** The calibration solves build and drop numpy arrays of
  0.1-1 MB thousands of times (Jacobians, normal equations). By default glibc serves each from a fresh
  ``mmap`` (above its 128 kB threshold) or gives the heap top back to the kernel on every free, and every
  reuse then faults its pages in again: 140 000 page faults and 0.2 s of kernel time in a 1.2 s, 40-pair
  calibration on 2 cores. Arrays below :data:`MMAP_THRESHOLD_BYTES` now come from the heap, and up to
  :data:`TRIM_THRESHOLD_BYTES` of free memory at the heap top stays mapped: 37 000 faults, 0.1-0.15 s less
  wall time. The peak is unchanged; what stays mapped after a burst of large arrays interleaved with small
  ones that live on can be more than that (the heap cannot shrink past a live block), as with glibc's own
  dynamic threshold once it has risen. Worker processes inherit the settings (fork). Nothing changes without
  glibc (musl, macOS) or when the user tuned malloc (``MALLOC_MMAP_THRESHOLD_``, ``MALLOC_TRIM_THRESHOLD_``
  or ``glibc.malloc`` tunables in ``GLIBC_TUNABLES``).
- **SIGTERM is an interrupt** (:func:`sigterm_as_interrupt`, around each command): ``timeout`` and ``kill`` send
  SIGTERM, whose default action ends the process at once, so ``.s2r-tmp-*`` temporaries stayed behind and the
  rerun was refused. It now raises :class:`Terminated` (a ``KeyboardInterrupt``) in the main thread, and every
  output is cleaned up the way Ctrl-C cleans it up; the exit code is 143 (128 + 15).
"""

from __future__ import annotations

import ctypes
import os
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

__all__ = ["MMAP_THRESHOLD_BYTES", "TRIM_THRESHOLD_BYTES", "Terminated", "sigterm_as_interrupt"]

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("PYDANTIC_DISABLE_PLUGINS", "__all__")

#: Allocations up to this size are served from the heap, not from a fresh mmap (bytes).
MMAP_THRESHOLD_BYTES = 32 << 20
#: Freed memory at the heap top up to this much is kept for reuse, not returned to the kernel (bytes).
TRIM_THRESHOLD_BYTES = 64 << 20
_M_TRIM_THRESHOLD = -1  # glibc's mallopt parameter numbers (malloc.h)
_M_MMAP_THRESHOLD = -3


def _glibc() -> bool:
    try:
        return os.confstr("CS_GNU_LIBC_VERSION") is not None
    except (AttributeError, ValueError, OSError):
        return False


def _tune_malloc() -> None:
    user = any(k in os.environ for k in ("MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_")) \
        or "glibc.malloc." in os.environ.get("GLIBC_TUNABLES", "")
    if user or not _glibc():
        return
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return
    mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES)
    mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD_BYTES)


_tune_malloc()


class Terminated(KeyboardInterrupt):
    """SIGTERM arrived: raised where Ctrl-C raises ``KeyboardInterrupt``, so the same clean-up runs."""


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Within the block, SIGTERM raises :class:`Terminated` in this process's main thread.

    Nothing changes when called from another thread or when SIGTERM already has a handler (a host program's).
    A forked child (a worker of a process pool) that inherited the handler ends as SIGTERM's default would.
    """
    if threading.current_thread() is not threading.main_thread() \
            or signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL:
        yield
        return
    owner = os.getpid()

    def interrupt(signum: int, frame: FrameType | None) -> None:
        if os.getpid() != owner:
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGTERM)
            return
        raise Terminated

    signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
