"""Corner detection of many images, parallel and cached (the detectors: :mod:`s2r.calib.detect.chessboard`,
:mod:`s2r.calib.detect.markers`).

Images up to twice 640x480 in area are detected at full resolution (as a plain OpenCV loop does);
larger ones first on a copy downscaled by an integer factor (INTER_AREA, as ROS camera_calibration
does) and the corners refined at full resolution. The classic detector
(``findChessboardCorners`` with ADAPTIVE_THRESH | NORMALIZE_IMAGE | FAST_CHECK) runs first (on large
images also at full resolution, for steeply tilted boards), the sector-based ``findChessboardCornersSB``
(NORMALIZE_IMAGE) is the fallback, on images larger than 640x480 only when OpenCV's quick check
(``checkChessboard``) finds a board likely, so frames without a board cost about one FAST_CHECK call.
``cornerSubPix`` uses a window fitted to the board: 0.4 x the smallest distance between neighbouring
corners, clamped to 2..11 px (half-size), instead of a fixed 11x11 (half-size) window that would swallow
neighbouring corners of small or distant boards.

Corner arrays are (N, 2) float32 pixel coordinates (OpenCV convention, 0-based pixel centres), row-major
over the pattern's ``(cols, rows)`` inner corners.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import logging
from collections import deque
from collections.abc import Iterable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.detect import cache
from s2r.calib.detect.chessboard import detect_board
from s2r.cvpool import opencv_pool
from s2r.errors import S2RError
from s2r.fileio import atomic_write_text
from s2r.imageio import decode_image_file
from s2r.progress import ProgressCallback, report

if TYPE_CHECKING:
    from s2r.targets import AnyTarget

__all__ = [
    "DETECTOR_VERSION",
    "CornerCache",
    "DetectItem",
    "Detection",
    "detect_stream",
]

log = logging.getLogger(__name__)

#: Bumped whenever detection changes so stale cache entries are ignored.
DETECTOR_VERSION = 7

Status = Literal["ok", "no_board", "unreadable"]
Corners = NDArray[np.float32]


@dataclass(frozen=True)
class Detection:
    """Detection result of one image.

    ``size`` is ``(width, height)`` in pixels (None when unreadable); ``corners`` (N, 2) float32 pixels
    when ``status == "ok"``; ``detector`` is ``"classic"``, ``"classic-full"``, ``"sb"`` or ``"classic-plain"``;
    ``detail`` says why it failed. ``ids`` (N,) int32 are the target's corner ids of ``corners`` when a file-described
    target (``--target``) was detected; None for a ``--pattern`` chessboard (all corners, row-major).
    """

    name: str
    sha256: str
    status: Status
    size: tuple[int, int] | None = None
    corners: Corners | None = None
    detector: str = ""
    detail: str = ""
    cached: bool = False
    ids: NDArray[np.int32] | None = None


@dataclass(frozen=True)
class DetectItem:
    """One image to detect: a display ``name``, its content ``sha256`` and either a file path or a
    decoded 8-bit grey image (H, W) (bag frames)."""

    name: str
    sha256: str
    source: Path | NDArray[np.uint8]


def _detect_item(item: DetectItem, pattern: tuple[int, int], target: AnyTarget | None = None) -> Detection:
    """Worker: read (if a path), detect (``target`` when given, else the ``pattern`` chessboard), describe."""
    if isinstance(item.source, Path):
        gray, reason = decode_image_file(item.source, cv2.IMREAD_GRAYSCALE)
        if gray is None:
            return Detection(item.name, item.sha256, "unreadable", detail=f"not a readable image: {reason}")
    else:
        gray = item.source
    size = (int(gray.shape[1]), int(gray.shape[0]))
    if target is not None:
        from s2r.calib.detect.markers import detect_target  # local: loads the target models (pydantic)

        found, name = detect_target(np.ascontiguousarray(gray, np.uint8), target)
        if found is None:
            return Detection(item.name, item.sha256, "no_board", size=size, detector=name,
                             detail=f"no {target.describe()} found (or too few corners)")
        return Detection(item.name, item.sha256, "ok", size=size, corners=found[1], detector=name, ids=found[0])
    corners, detector = detect_board(np.ascontiguousarray(gray, np.uint8), pattern)
    if corners is None:
        return Detection(item.name, item.sha256, "no_board", size=size,
                         detail=f"no {pattern[0]}x{pattern[1]} chessboard found")
    return Detection(item.name, item.sha256, "ok", size=size, corners=corners, detector=detector)


class CornerCache:
    """Per-image detection results on disk, one small JSON file per (content sha256, pattern, version).

    Each result is written atomically as soon as it is known, so an interrupted run keeps every finished
    detection and a re-run (e.g. with other solver options) reads them back instead of detecting again.
    """

    def __init__(self, folder: Path, target: AnyTarget | None = None) -> None:
        self.folder = Path(folder)
        if target is not None:
            from s2r.targets import DETECTOR_REVISION
        self.target_key = "" if target is None else hashlib.sha256(
            f"{DETECTOR_REVISION}|{target.model_dump_json()}".encode()).hexdigest()[:16]
        self.usable = cache.folder_usable(self.folder)
        if not self.usable:
            log.warning("%s is a symbolic link or not a folder: the corner cache is not used (nothing is read "
                        "from or written through it)", self.folder)
        self.remove_stale_temporaries()

    def remove_stale_temporaries(self, max_age_s: float = 60.0) -> int:
        """Delete s2r's own half-written entries older than ``max_age_s`` (left by a killed run); their count."""
        return cache.remove_stale_temporaries(self.folder, max_age_s=max_age_s) if self.usable else 0

    def _file(self, sha256: str, pattern: tuple[int, int]) -> Path:
        board = f"t{self.target_key}" if self.target_key else f"{pattern[0]}x{pattern[1]}"
        return self.folder / f"{sha256}-{board}-v{DETECTOR_VERSION}.json"

    def get(self, name: str, sha256: str, pattern: tuple[int, int]) -> Detection | None:
        """The cached detection of this content, renamed to ``name``, or None (also for an entry that is not a
        regular file or fails validation: see :mod:`s2r.calib.detect.cache`)."""
        path = self._file(sha256, pattern)
        data = cache.read_entry(self.folder, path.name) if self.usable else None
        if data is None:
            return None
        try:
            entry = cache.validate_entry(data, corner_count=None if self.target_key else pattern[0] * pattern[1],
                                         with_ids=bool(self.target_key))
        except ValueError as exc:
            log.debug("corner cache entry %s ignored (detected again): %s", path, exc)
            return None
        corners = None if entry["corners"] is None else np.asarray(entry["corners"], np.float32).reshape(-1, 2)
        ids = None if entry["ids"] is None else np.asarray(entry["ids"], np.int32).reshape(-1)
        return Detection(name, sha256, entry["status"], size=entry["size"], corners=corners,
                         detector=entry["detector"], detail=entry["detail"], cached=True, ids=ids)

    def put(self, det: Detection, pattern: tuple[int, int]) -> None:
        """Store ``det`` (atomic write; a failure to write the cache is not an error)."""
        if not self.usable or not cache.folder_usable(self.folder):
            return
        data: dict[str, Any] = {"status": det.status, "size": det.size, "detector": det.detector,
                                "detail": det.detail,
                                "corners": None if det.corners is None else det.corners.round(4).tolist()}
        if det.ids is not None:
            data["ids"] = det.ids.astype(int).tolist()
        with contextlib.suppress(OSError, S2RError):  # not synced: an entry a power loss tore fails to parse
            atomic_write_text(self._file(det.sha256, pattern), json.dumps(data), force=True, root=self.folder,
                              durable=False)


def detect_stream(items: Iterable[DetectItem], *, pattern: tuple[int, int], jobs: int = 1,
                  cache: CornerCache | None = None, total: int | None = None,
                  progress: ProgressCallback | None = None, target: AnyTarget | None = None,
                  pool: ProcessPoolExecutor | None = None) -> Iterator[Detection]:
    """Detect every item, in input order, over ``jobs`` worker processes (the ``target``'s corners with
    their ids when given, else the ``pattern`` chessboard; a cache must then be made for that target); in
    ``pool`` when given (the caller's, already started: it shuts it down), else in a pool of its own.

    Items are consumed lazily and at most ``4 * jobs`` are in flight, so images are never all in memory.
    Cache hits skip detection; each new result is written to the cache the moment its worker finishes.
    """
    pending: deque[Detection | Future[Detection]] = deque()
    window = max(1, 4 * jobs)
    done = 0
    workers = contextlib.ExitStack()

    def store(fut: Future[Detection]) -> None:
        # runs as soon as a worker finishes (even ahead of earlier items), so an interrupt loses nothing done
        if cache is not None and not fut.cancelled() and fut.exception() is None:
            cache.put(fut.result(), pattern)

    def finish(entry: Detection | Future[Detection]) -> Detection:
        nonlocal done
        if isinstance(entry, Detection):
            det = entry
            if cache is not None and not det.cached:
                cache.put(det, pattern)
        else:
            det = entry.result()
        done += 1
        report(progress, done, total or done, "detecting corners")
        return det

    try:
        for item in items:
            hit = cache.get(item.name, item.sha256, pattern) if cache is not None else None
            if hit is not None:
                pending.append(hit)
            elif jobs <= 1:
                pending.append(_detect_item(item, pattern, target))
            else:
                pool = pool or workers.enter_context(opencv_pool(jobs))
                future = pool.submit(_detect_item, item, pattern, target)
                future.add_done_callback(store)
                pending.append(future)
            while len(pending) >= window or (pending and isinstance(pending[0], Detection)):
                yield finish(pending.popleft())
        while pending:
            yield finish(pending.popleft())
    finally:
        workers.close()
