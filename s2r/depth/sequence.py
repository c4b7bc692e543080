"""Depth for a sequence of stereo pairs: read, compute and write in overlapped stages on threads.

OpenCV releases the GIL inside imdecode, remap, the matchers and imencode, so a reader thread, ``workers``
compute threads and a writer thread keep both cores busy while frames stream through in order.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from s2r.depth.outputs import IMAGE_SUFFIXES, read_image, write_outputs
from s2r.depth.pipeline import DepthResult, StereoPipeline
from s2r.errors import DepthError
from s2r.fileio import OutputBatch
from s2r.progress import ProgressCallback, report

__all__ = ["frame_prefix", "pair_images", "run_sequence"]

Pair = tuple[NDArray[np.uint8], NDArray[np.uint8]]


def _images(folder: Path, field: str) -> list[Path]:
    if not folder.is_dir():
        raise DepthError("not a folder", path=folder, field=field, hint="pass a folder of images")
    return sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES)


def pair_images(left_dir: str | Path, right_dir: str | Path) -> list[tuple[Path, Path]]:
    """Pair the images of two folders by sorted file name (the n-th left with the n-th right)."""
    lefts, rights = _images(Path(left_dir), "left-dir"), _images(Path(right_dir), "right-dir")
    if not lefts:
        raise DepthError("no images found", path=left_dir, hint=f"expected files ending {', '.join(IMAGE_SUFFIXES)}")
    if len(lefts) != len(rights):
        raise DepthError(f"{len(lefts)} left images but {len(rights)} right images", path=right_dir,
                         hint="both folders need one image per frame")
    return list(zip(lefts, rights, strict=True))


def frame_prefix(index: int, total: int) -> str:
    """Output prefix of frame ``index`` (0-based), zero-padded to at least two digits: ``07_``."""
    return f"{index:0{max(2, len(str(max(total - 1, 0))))}d}_"


def run_sequence(
    pipeline: StereoPipeline,
    pairs: list[tuple[Path, Path]],
    out_dir: str | Path,
    *,
    ply: bool = False,
    force: bool = False,
    workers: int = 2,
    progress: ProgressCallback | None = None,
    depth_range_m: tuple[float, float] | None = None,
    batch: OutputBatch | None = None,
    colour_range_m: tuple[float, float] | None = None,
) -> int:
    """Compute and write ``NN_disparity.npy``, ``NN_depth.png``, ``NN_depth_color.png`` (``NN_points.ply``)
    for every pair, in order (depths outside ``depth_range_m`` invalid; ``colour_range_m`` (near, far) m fixes
    the colour scale of every frame); returns the number of frames written.
    Errors (unreadable image, size mismatch)
    propagate from the frame that failed; frames not yet started are cancelled. With ``batch`` every frame is
    staged there (the caller publishes the whole sequence); without, each frame's files are published alone."""
    out = Path(out_dir)
    total = len(pairs)
    pending: deque[Future[list[Path]]] = deque()
    reader = ThreadPoolExecutor(1, thread_name_prefix="s2r-read")
    computer = ThreadPoolExecutor(max(1, workers), thread_name_prefix="s2r-depth")
    writer = ThreadPoolExecutor(1, thread_name_prefix="s2r-write")
    done = 0
    try:
        for index, (left, right) in enumerate(pairs):
            read = reader.submit(_read_pair, left, right)
            computed = computer.submit(_compute_after, pipeline, read, left)
            prefix = frame_prefix(index, total)
            pending.append(writer.submit(_write_after(out, computed, prefix, ply=ply, force=force,
                                                      depth_range_m=depth_range_m, batch=batch,
                                                      colour_range_m=colour_range_m)))
            while len(pending) > 2 * workers + 2:
                pending.popleft().result()
                done += 1
                report(progress, done, total, "depth")
        while pending:
            pending.popleft().result()
            done += 1
            report(progress, done, total, "depth")
    finally:
        for pool in (reader, computer, writer):
            pool.shutdown(wait=True, cancel_futures=True)
    return done


def _read_pair(left: Path, right: Path) -> Pair:
    return read_image(left), read_image(right)


def _compute_after(pipeline: StereoPipeline, read: Future[Pair], left: Path) -> DepthResult:
    try:
        return pipeline.compute(*read.result())
    except DepthError as exc:  # e.g. one frame of another size: say which file
        if exc.path is not None:
            raise
        raise DepthError(exc.message, path=left, field=exc.field, hint=exc.hint) from None


def _write_after(out: Path, computed: Future[DepthResult], prefix: str, *, ply: bool, force: bool,
                 depth_range_m: tuple[float, float] | None = None,
                 batch: OutputBatch | None = None, colour_range_m: tuple[float, float] | None = None
                 ) -> Callable[[], list[Path]]:
    return lambda: write_outputs(out, computed.result(), prefix=prefix, ply=ply, force=force,
                                 depth_range_m=depth_range_m, batch=batch, colour_range_m=colour_range_m)
