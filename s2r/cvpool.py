"""The local process pool for OpenCV work (calibrate's detection and fold solves, check's feature matching).

Each worker runs one image, pair or solve at a time and there are as many workers as cores, so OpenCV's own
thread pool inside a worker only oversubscribes the cores: its threads spin (``sched_yield``) waiting for work,
about 10 % of a 40-pair calibration's CPU time on 2 cores. ``cv2.setNumThreads`` must not be called in a forked
child (see :func:`s2r.executor.local_pool`), so this process sets one thread before its workers fork and restores
its own setting when the pool is shut down.
"""

from __future__ import annotations

from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager

import cv2

from s2r.executor import local_pool

__all__ = ["opencv_pool"]


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
