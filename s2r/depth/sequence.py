"""Depth for a folder sequence of stereo pairs (``--left-dir/--right-dir``): the stream engine of
:mod:`s2r.depth.stream` over the pairs, written as ``NN_*`` files.

OpenCV releases the GIL inside imdecode, remap, the matchers and imencode, so the reader thread, ``workers``
compute threads and the writing thread keep both cores busy while frames stream through in order.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

from s2r.depth.outputs import IMAGE_SUFFIXES, read_image, write_outputs
from s2r.depth.pipeline import StereoPipeline
from s2r.depth.stream import depth_frames
from s2r.errors import DepthError
from s2r.fileio import OutputBatch, protect_read_files
from s2r.progress import ProgressCallback, report
from s2r.recordings.frames import StereoFrame

__all__ = ["frame_prefix", "pair_frames", "pair_images", "run_sequence"]


def _images(folder: Path, field: str) -> list[Path]:
    if not folder.is_dir():
        raise DepthError("not a folder", path=folder, field=field, hint="pass a folder of images")
    images = sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES)
    protect_read_files(images)  # inputs of the running command: no output may be one of them
    return images


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


def pair_frames(pairs: list[tuple[Path, Path]]) -> Iterator[StereoFrame]:
    """The pairs as :class:`StereoFrame` values read one at a time (no stamps; named after the left file)."""
    for index, (left, right) in enumerate(pairs):
        yield StereoFrame(index=index, name=left.stem, stamp_ns=None, frame_id="", left=read_image(left),
                          right=read_image(right), source=str(left))


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

    Reading, matching and writing overlap through :func:`s2r.depth.stream.depth_frames` (a reader thread,
    ``workers`` matching threads, the writes in this thread). Errors (unreadable image, size mismatch) propagate
    from the frame that failed; frames not yet started are cancelled. With ``batch`` every frame is staged there
    (the caller publishes the whole sequence); without, each frame's files are published alone."""
    out = Path(out_dir)
    total = len(pairs)
    done = 0
    for frame in depth_frames(pipeline, pair_frames(pairs), workers=workers, depth_range_m=depth_range_m):
        write_outputs(out, frame.result, prefix=frame_prefix(frame.index, total), ply=ply, force=force, batch=batch,
                      colour_range_m=colour_range_m)
        done += 1
        report(progress, done, total, "depth")
    return done
