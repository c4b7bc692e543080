"""Stereo calibration from a frame stream (videos, or any :class:`~s2r.recordings.FrameSource`).

Frames are read one at a time; a blurred pair (:mod:`s2r.calib.detect.sharpness`) is skipped before detection;
the others go to the parallel cached detector (keyed by the sha256 of the decoded pixels). Consecutive frames whose
corners lie within :data:`~s2r.calib.solve.views.REPEAT_PX` of the frame before (a board held still while the
camera records) are one view: the repeated-view rule of the solve, applied along the stream so a still board
filmed for seconds becomes one view and one line. The result's ``frames`` figure says how many frames were read,
how many became views, and why the others did not.
"""

from __future__ import annotations

import hashlib
from collections import Counter
from collections.abc import Iterator, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.calib.detect import CornerCache, Detection, DetectItem, detect_stream
from s2r.calib.detect.sharpness import BLUR_RATIO, BlurFilter
from s2r.calib.solve.pipelines.stereo import StereoCalibration, calibrate_stereo_detections
from s2r.calib.solve.views import REPEAT_PX, repeat_distance
from s2r.errors import CalibrationError
from s2r.executor import usable_cores
from s2r.lens.models import DEFAULT_LENS
from s2r.profile import DroppedView, SourceFile
from s2r.progress import ProgressCallback
from s2r.recordings import FrameSource
from s2r.targets import AnyTarget

__all__ = ["calibrate_stereo_stream"]

Pair = tuple[str, Detection, Detection]
_SAMPLES = 16
#: Bytes of sample images kept for the report (the first pairs, at least one): 16 pairs of 8192x8192 px would
#: hold 2 GiB while the stream is detected.
_SAMPLE_BYTES = 64 << 20
_RUN = "consecutive frame(s)"


def _sha(image: NDArray[np.uint8]) -> str:
    return hashlib.sha256(np.ascontiguousarray(image).tobytes() + repr(image.shape).encode()).hexdigest()


def _still(a: Pair, b: Pair) -> float | None:
    """The corner distance (px) of two pairs both detected in both cameras with the same corners, else None."""
    dets = (a[1], b[1], a[2], b[2])
    if any(d.status != "ok" or d.corners is None for d in dets):
        return None
    if a[1].corners.shape != b[1].corners.shape or a[2].corners.shape != b[2].corners.shape:  # type: ignore[union-attr]
        return None
    for x, y in ((a[1].ids, b[1].ids), (a[2].ids, b[2].ids)):
        if (x is None) != (y is None) or (x is not None and y is not None and not np.array_equal(x, y)):
            return None
    return max(repeat_distance(a[1].corners, b[1].corners), repeat_distance(a[2].corners, b[2].corners))  # type: ignore[arg-type]


def merge_still_runs(pairs: Sequence[Pair]) -> tuple[list[Pair], list[DroppedView], int]:
    """Pairs without the consecutive repeats of the pair before them (module docstring), one DroppedView per run of
    repeats, and the number of frames merged."""
    kept: list[Pair] = []
    runs: dict[str, list[tuple[str, float]]] = {}
    for pair in pairs:
        dist = _still(kept[-1], pair) if kept else None
        if dist is not None and dist < REPEAT_PX:
            runs.setdefault(kept[-1][0], []).append((pair[0], dist))
            continue
        kept.append(pair)
    dropped = [DroppedView(name=f"{run[0][0]}..{run[-1][0]}" if len(run) > 1 else run[0][0],
                           rms_px=max(d for _, d in run),
                           reason=f"repeat of {first}: {len(run)} {_RUN} whose corners lie within a "
                                  f"median {max(d for _, d in run):.3f} px of it (a still board); one view")
               for first, run in runs.items()]
    return kept, dropped, sum(len(r) for r in runs.values())


def _kind(reason: str) -> str:
    """A dropped view's reason in a word or two, for the frame counts."""
    for prefix, kind in (("repeat of", "repeat"), ("blurred", "blurred"), ("outlier", "outlier"),
                         ("mismatched", "mismatched")):
        if reason.startswith(prefix):
            return kind
    return reason.split(":")[0].split("(")[0].strip()[:60] or "other"


def frame_counts(read: int, result: StereoCalibration, merged: int, blur_ratio: float) -> dict[str, Any]:
    """The ``frames`` figure: frames read, views used, and the frames not kept counted by reason (``merged``
    consecutive repeats counted one by one, not per run)."""
    counts: Counter[str] = Counter(_kind(d.reason) for d in result.dropped if _RUN not in d.reason)
    counts["repeat"] += merged
    return {"read": read, "views_used": len(result.used_names),
            "not_kept": {k: v for k, v in sorted(counts.items()) if v > 0}, "blur_ratio": blur_ratio}


def calibrate_stereo_stream(
    source: FrameSource, *, sources: Sequence[SourceFile] = (), blur_ratio: float = BLUR_RATIO,
    pattern: tuple[int, int] = (9, 6), square_m: float = 0.025, name: str = "calibrated",
    distortion: str = DEFAULT_LENS, max_error_px: float | None = None, fix_intrinsics: bool = False,
    swap: bool = False, jobs: int | None = None, cache_dir: Path | None = None,
    progress: ProgressCallback | None = None, target: AnyTarget | None = None, lens: str = "pinhole",
    total: int | None = None,
) -> StereoCalibration:
    """Calibrate a stereo pair from the frames of ``source`` (module docstring); options as
    :func:`s2r.calib.calibrate_stereo` (``target``/``lens`` as :mod:`s2r.calib.solve.pipelines.target_stereo`).

    Args:
        sources: the input files hashed into the profile's provenance.
        blur_ratio: :class:`~s2r.calib.detect.sharpness.BlurFilter`'s ratio (0: the absolute floor only).
        total: frames expected, for the progress bar.

    Raises:
        CalibrationError: no frames, and the usual calibration input errors.
    """
    blur = BlurFilter(ratio=blur_ratio)
    blurred: list[DroppedView] = []
    names: list[str] = []
    samples: dict[str, tuple[NDArray[np.uint8], NDArray[np.uint8]]] = {}

    def items() -> Iterator[DetectItem]:
        for frame in source.frames():
            if why := blur.reason(frame.left, frame.right):
                blurred.append(DroppedView(name=frame.name, reason=why))
                continue
            names.append(frame.name)
            if len(samples) < _SAMPLES and (not samples or (len(samples) + 1) * 2 * frame.left.nbytes <= _SAMPLE_BYTES):
                samples[frame.name] = (frame.left, frame.right)
            yield DetectItem(name=f"{frame.name} left", sha256=_sha(frame.left), source=frame.left)
            yield DetectItem(name=f"{frame.name} right", sha256=_sha(frame.right), source=frame.right)

    cache = CornerCache(cache_dir, target) if cache_dir is not None else None
    dets = list(detect_stream(items(), pattern=pattern, jobs=jobs or usable_cores(), cache=cache,
                              total=None if total is None else 2 * total, progress=progress, target=target))
    read = len(names) + len(blurred)
    if not read:
        raise CalibrationError("the recording holds no frames", path=source.describe(), hint="check the input")
    pairs, repeats, merged = merge_still_runs([(n, dets[2 * i], dets[2 * i + 1]) for i, n in enumerate(names)])
    result = _solve(pairs, [*blurred, *repeats], sources=sources, pattern=pattern, square_m=square_m, name=name,
                    distortion=distortion, max_error_px=max_error_px, fix_intrinsics=fix_intrinsics, swap=swap,
                    jobs=jobs, target=target, lens=lens)
    sample = next((samples[n] for n in result.used_names if n in samples), None)
    if sample is not None and swap:
        sample = (sample[1], sample[0])
    return replace(result, sample_images=sample, frames=frame_counts(read, result, merged, blur_ratio))


def _solve(pairs: list[Pair], dropped: list[DroppedView], *, sources: Sequence[SourceFile], pattern: tuple[int, int],
           square_m: float, name: str, distortion: str, max_error_px: float | None, fix_intrinsics: bool, swap: bool,
           jobs: int | None, target: AnyTarget | None, lens: str) -> StereoCalibration:
    if target is not None:
        from s2r.calib.solve.pipelines.target_stereo import calibrate_stereo_target_detections

        return calibrate_stereo_target_detections(
            pairs, target=target, lens=lens, distortion=distortion, name=name, max_error_px=max_error_px,
            fix_intrinsics=fix_intrinsics, swap=swap, sources=sources, extra_dropped=dropped,
            jobs=jobs or usable_cores())
    return calibrate_stereo_detections(
        pairs, pattern=pattern, square_m=square_m, name=name, distortion=distortion, max_error_px=max_error_px,
        fix_intrinsics=fix_intrinsics, swap=swap, sources=sources, extra_dropped=dropped,
        jobs=jobs or usable_cores())
