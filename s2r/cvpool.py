"""The local process pool for OpenCV work (calibrate's detection and fold solves, check's feature matching).

Each worker runs one image, pair or solve at a time and there are as many workers as cores, so OpenCV's own
thread pool inside a worker only oversubscribes the cores: its threads spin (``sched_yield``) waiting for work,
about 10 % of a 40-pair calibration's CPU time on 2 cores. ``cv2.setNumThreads`` must not be called in a forked
child (see :func:`s2r.executor.local_pool`), so this process sets one thread before its workers fork and restores
its own setting when the pool is shut down.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import ExitStack, contextmanager

import cv2

from s2r.executor import WorkersUnavailable, local_pool

__all__ = ["opencv_pool", "opencv_pool_or_none"]

log = logging.getLogger(__name__)


@contextmanager
def opencv_pool(jobs: int) -> Iterator[ProcessPoolExecutor]:
    """:func:`s2r.executor.local_pool` of ``jobs`` workers whose OpenCV runs single-threaded; shut down on exit
    (pending work cancelled) and this process's OpenCV thread count restored."""
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    pool = local_pool(jobs)
    try:
        yield pool
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        cv2.setNumThreads(threads)


def opencv_pool_or_none(jobs: int, stack: ExitStack, what: str) -> ProcessPoolExecutor | None:
    """:func:`opencv_pool` entered on ``stack``, or None when ``jobs`` is 1 or worker processes cannot start here
    (no writable ``/dev/shm``: a warning then says that ``what``, e.g. "matching", runs in one process)."""
    if jobs <= 1:
        return None
    try:
        return stack.enter_context(opencv_pool(jobs))
    except WorkersUnavailable as exc:
        log.warning("%s: %s in one process", exc.message, what)
        return None
