"""Progress reporting without printing: library code calls a callback, the CLI draws the bar."""

from __future__ import annotations

from collections.abc import Callable

__all__ = ["ProgressCallback", "report"]

#: ``callback(done, total, label)``: ``done`` of ``total`` items finished, ``label`` names the stage.
ProgressCallback = Callable[[int, int, str], None]


def report(callback: ProgressCallback | None, done: int, total: int, label: str) -> None:
    """Call ``callback`` if there is one; a no-op otherwise."""
    if callback is not None:
        callback(done, total, label)
