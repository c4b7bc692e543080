"""Run render jobs in parallel processes (one PyBullet connection per worker, reused across its jobs)."""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable, Sequence
from concurrent.futures import as_completed
from typing import TypeVar

from s2r.errors import RenderError
from s2r.executor import local_pool, usable_cores
from s2r.progress import ProgressCallback, report

__all__ = ["resolve_jobs", "run_jobs"]

ItemT = TypeVar("ItemT")
ResultT = TypeVar("ResultT")


def resolve_jobs(jobs: int | None, count: int) -> int:
    """Worker count: ``jobs`` (default the usable cores), at most ``count``, at least 1 (1 inside a
    daemonic pool worker, which may not start processes)."""
    if jobs is not None and jobs < 1:
        raise RenderError(f"jobs must be at least 1, got {jobs}", field="jobs", hint="pass --jobs 1 or more")
    wanted = jobs if jobs is not None else usable_cores()
    if multiprocessing.current_process().daemon:
        return 1  # a pool worker cannot start its own pool: render in this process
    return max(1, min(wanted, count))


def run_jobs(
    fn: Callable[[ItemT], ResultT], items: Sequence[ItemT], *, jobs: int | None, progress: ProgressCallback | None,
    label: str,
) -> list[ResultT]:
    """``[fn(item) for item in items]``, in ``jobs`` processes (``jobs=1``: in this process), in order.

    ``fn`` must be a module-level function and ``items`` picklable. Progress is reported per finished item.
    """
    total = len(items)
    workers = resolve_jobs(jobs, total)
    report(progress, 0, total, label)
    if workers == 1:
        results: list[ResultT] = []
        for item in items:
            results.append(fn(item))
            report(progress, len(results), total, label)
        return results
    slots: list[ResultT | None] = [None] * total
    with local_pool(workers) as pool:
        futures = {pool.submit(fn, item): k for k, item in enumerate(items)}
        for done, future in enumerate(as_completed(futures), start=1):
            slots[futures[future]] = future.result()
            report(progress, done, total, label)
    return [r for r in slots if r is not None]
