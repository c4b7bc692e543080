"""Detection of stereo image files, started at once and run in the background.

A caller starts :class:`PairDetection` and does other work while the workers detect: ``s2r calibrate`` loads
the solver's modules (about 0.2 s, a quarter of a 40-pair first run on 2 cores) in that time. The worker
processes are forked when the detection starts, in the calling thread and before the background thread
exists, so no other thread of this process can hold a lock (an import's, logging's) that a forked worker would
inherit locked. The background thread only hashes the files (the corner cache's key), submits them and
collects the results in input order.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from s2r.calib.detect.stream import CornerCache, Detection, DetectItem, detect_stream
from s2r.cvpool import opencv_pool_or_none
from s2r.errors import CalibrationError
from s2r.executor import usable_cores
from s2r.fileio import sha256_file
from s2r.progress import ProgressCallback

__all__ = ["DetectedPairs", "PairDetection", "display_name"]


def display_name(path: Path) -> str:
    """``folder/file``: how a view's image is named in the figures (the file name alone at the root)."""
    return f"{path.parent.name}/{path.name}" if path.parent.name else path.name


@dataclass(frozen=True)
class DetectedPairs:
    """Every pair's ``(name, left detection, right detection)`` in input order, the content sha256 of each
    file, and the files as detected (``left``/``right`` exchanged when ``swap`` was asked)."""

    pairs: list[tuple[str, Detection, Detection]]
    sha256: dict[Path, str]
    left: tuple[Path, ...]
    right: tuple[Path, ...]
    unpaired: tuple[Path, ...]


class PairDetection:
    """Corner detection of ``left_paths[i]`` / ``right_paths[i]``, started by the constructor.

    Args:
        pattern: chessboard inner corners ``(cols, rows)``; jobs: worker processes (default all cores; 1
            detects in the background thread itself); cache_dir: the per-image corner cache folder.
        names: pair labels (default the left file stems); unpaired: files without a partner (reported by
            the solve as dropped); swap: exchange left and right before detecting.

    Raises:
        CalibrationError: unequal numbers of left and right files (before anything starts).
    """

    def __init__(self, left_paths: Sequence[Path], right_paths: Sequence[Path], *, pattern: tuple[int, int],
                 jobs: int | None = None, cache_dir: Path | None = None, progress: ProgressCallback | None = None,
                 names: Sequence[str] | None = None, unpaired: Sequence[Path] = (), swap: bool = False) -> None:
        if swap:
            left_paths, right_paths = right_paths, left_paths
        if len(left_paths) != len(right_paths):
            raise CalibrationError(f"{len(left_paths)} left but {len(right_paths)} right images",
                                   hint="pass the same number of left and right images")
        self.left, self.right = tuple(Path(p) for p in left_paths), tuple(Path(p) for p in right_paths)
        self.unpaired = tuple(Path(p) for p in unpaired)
        self.pattern = pattern
        self._names = list(names) if names is not None else [p.stem for p in self.left]
        self._sha256: dict[Path, str] = {}
        self._pairs: list[tuple[str, Detection, Detection]] = []
        self._error: BaseException | None = None
        self._stop = threading.Event()
        self._workers = contextlib.ExitStack()
        jobs = jobs or usable_cores()
        cache = CornerCache(cache_dir) if cache_dir is not None else None
        pool = None
        if jobs > 1 and self.left:
            pool = opencv_pool_or_none(jobs, self._workers, "detecting")  # forks now, from this thread (module doc)
            jobs = jobs if pool is not None else 1
        self._thread = threading.Thread(target=self._run, args=(jobs, cache, progress, pool),
                                        name="s2r-detection", daemon=True)
        self._thread.start()

    def _items(self) -> Iterator[DetectItem]:
        for pl, pr in zip(self.left, self.right, strict=True):
            for p in (pl, pr):
                if self._stop.is_set():
                    return
                self._sha256[p] = sha256_file(p)
                yield DetectItem(name=display_name(p), sha256=self._sha256[p], source=p)

    def _run(self, jobs: int, cache: CornerCache | None, progress: ProgressCallback | None,
             pool: ProcessPoolExecutor | None) -> None:
        try:
            stream = detect_stream(self._items(), pattern=self.pattern, jobs=jobs, cache=cache,
                                   total=2 * len(self.left), progress=progress, pool=pool)
            it = iter(stream)
            for name in self._names:
                self._pairs.append((name, next(it), next(it)))
        except StopIteration:
            pass  # cancelled: the items ran out early
        except BaseException as exc:  # handed to the thread that asks for the result
            self._error = exc

    def result(self) -> DetectedPairs:
        """Wait for every detection (an interrupt cancels the rest and is raised); the workers end here."""
        try:
            while self._thread.is_alive():
                self._thread.join(timeout=0.1)
        except BaseException:
            self.cancel()
            raise
        finally:
            self._workers.close()
        if self._error is not None:
            raise self._error
        return DetectedPairs(self._pairs, dict(self._sha256), self.left, self.right, self.unpaired)

    def cancel(self) -> None:
        """Stop feeding the workers and end them (detections in flight are dropped)."""
        self._stop.set()
        self._thread.join()
        self._workers.close()
