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
import ctypes
import hashlib
import json
import multiprocessing as mp
import os
import signal
import sys
import threading
import time
from collections import deque
from collections.abc import Iterable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.calib.detect.chessboard import detect_board
from s2r.calib.detect.markers import detect_target
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
    "process_pool",
]

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
        self.remove_stale_temporaries()

    def remove_stale_temporaries(self, max_age_s: float = 60.0) -> int:
        """Delete half-written ``.*.tmp`` files older than ``max_age_s`` (left by a killed run); their count."""
        removed = 0
        now = time.time()
        with contextlib.suppress(OSError):
            for tmp in self.folder.glob(".*.tmp"):
                with contextlib.suppress(OSError):
                    if now - tmp.lstat().st_mtime > max_age_s:
                        tmp.unlink()
                        removed += 1
        return removed

    def _file(self, sha256: str, pattern: tuple[int, int]) -> Path:
        board = f"t{self.target_key}" if self.target_key else f"{pattern[0]}x{pattern[1]}"
        return self.folder / f"{sha256}-{board}-v{DETECTOR_VERSION}.json"

    def get(self, name: str, sha256: str, pattern: tuple[int, int]) -> Detection | None:
        """The cached detection of this content, renamed to ``name``, or None."""
        try:
            data = json.loads(self._file(sha256, pattern).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        corners = None if data.get("corners") is None else np.asarray(data["corners"], np.float32).reshape(-1, 2)
        size = None if data.get("size") is None else (int(data["size"][0]), int(data["size"][1]))
        ids = None if data.get("ids") is None else np.asarray(data["ids"], np.int32).reshape(-1)
        if self.target_key and corners is not None and (ids is None or len(ids) != len(corners)):
            return None  # a target's entry must carry one id per corner
        return Detection(name, sha256, data["status"], size=size, corners=corners,
                         detector=data.get("detector", ""), detail=data.get("detail", ""), cached=True, ids=ids)

    def put(self, det: Detection, pattern: tuple[int, int]) -> None:
        """Store ``det`` (atomic write; a failure to write the cache is not an error)."""
        data: dict[str, Any] = {"status": det.status, "size": det.size, "detector": det.detector,
                                "detail": det.detail,
                                "corners": None if det.corners is None else det.corners.round(4).tolist()}
        if det.ids is not None:
            data["ids"] = det.ids.astype(int).tolist()
        with contextlib.suppress(OSError, S2RError):
            atomic_write_text(self._file(det.sha256, pattern), json.dumps(data), force=True)


_PR_SET_PDEATHSIG = 1  # linux/prctl.h
_WATCHDOG_PERIOD_S = 1.0


def _die_with_parent(parent_pid: int) -> None:
    """Pool initializer: end this worker when the parent process dies, even by ``kill -9``.

    On Linux the kernel sends SIGKILL when the parent goes (``prctl(PR_SET_PDEATHSIG)``); everywhere a daemon
    thread also watches the parent pid once a second and exits when the worker was re-parented.
    """
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent_pid:  # the parent died before the line above took effect
        os._exit(1)

    def watch() -> None:
        while True:
            time.sleep(_WATCHDOG_PERIOD_S)
            if os.getppid() != parent_pid:
                os._exit(1)

    threading.Thread(target=watch, name="s2r-parent-watchdog", daemon=True).start()


def _executor(jobs: int) -> ProcessPoolExecutor:
    # fork: workers start instantly with cv2 loaded and never re-import the caller's __main__ (scripts
    # without a main guard keep working); spawn where fork does not exist. Never call cv2.setNumThreads in a
    # forked child: it waits for the parent's pool threads, which do not exist there, and hangs.
    ctx = mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn")
    return ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=_die_with_parent,
                               initargs=(os.getpid(),))


def process_pool(jobs: int) -> ProcessPoolExecutor:
    """s2r's one process pool (the detection workers' kind: forked, ended with the parent), for other
    parallel work such as the calibration's resampling solves; the caller shuts it down."""
    return _executor(jobs)


def detect_stream(items: Iterable[DetectItem], *, pattern: tuple[int, int], jobs: int = 1,
                  cache: CornerCache | None = None, total: int | None = None,
                  progress: ProgressCallback | None = None, target: AnyTarget | None = None) -> Iterator[Detection]:
    """Detect every item, in input order, over ``jobs`` worker processes (the ``target``'s corners with
    their ids when given, else the ``pattern`` chessboard; a cache must then be made for that target).

    Items are consumed lazily and at most ``4 * jobs`` are in flight, so images are never all in memory.
    Cache hits skip detection; each new result is written to the cache the moment its worker finishes.
    """
    pending: deque[Detection | Future[Detection]] = deque()
    window = max(1, 4 * jobs)
    done = 0
    pool: ProcessPoolExecutor | None = None

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
                pool = pool or _executor(jobs)
                future = pool.submit(_detect_item, item, pattern, target)
                future.add_done_callback(store)
                pending.append(future)
            while len(pending) >= window or (pending and isinstance(pending[0], Detection)):
                yield finish(pending.popleft())
        while pending:
            yield finish(pending.popleft())
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
