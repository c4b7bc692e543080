"""Stereo calibration from ROS bags: the image pairs of :mod:`s2r.recordings.bags` streamed to the detector
(the corner cache keyed by the sha256 of each message's serialized bytes), then the stereo solve.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from s2r.calib.detect import CornerCache, DetectItem, detect_stream
from s2r.calib.solve.pipelines.stereo import StereoCalibration, calibrate_stereo_detections
from s2r.errors import CalibrationError
from s2r.executor import usable_cores
from s2r.fileio import sha256_file
from s2r.lens.models import DEFAULT_LENS
from s2r.profile import SourceFile
from s2r.progress import ProgressCallback
from s2r.recordings.bagfiles import bag_storage_files
from s2r.recordings.bags import grey_of
from s2r.recordings.bagsource import BagFrames
from s2r.recordings.decode import SizeRule
from s2r.targets import AnyTarget

__all__ = ["calibrate_stereo_bag"]

_SAMPLES = 16
#: Bytes of sample images kept for the report (the first pairs, at least one): 16 pairs of 8192x8192 px would
#: hold 2 GiB while the stream is detected.
_SAMPLE_BYTES = 64 << 20


def _bag_sources(bag: Path) -> list[SourceFile]:
    """The bag's own storage files (never a file reached through a link out of its folder), hashed."""
    return [SourceFile(path=str(p), sha256=sha256_file(p)) for p in bag_storage_files(bag, error=CalibrationError)]


def calibrate_stereo_bag(
    bag: Path, *, left_topic: str, right_topic: str, max_dt_s: float = 0.01, every: int = 1,
    max_frames: int | None = None,
    pattern: tuple[int, int] = (9, 6), square_m: float = 0.025, name: str = "calibrated",
    distortion: str = DEFAULT_LENS, max_error_px: float | None = None, fix_intrinsics: bool = False,
    swap: bool = False,
    jobs: int | None = None, cache_dir: Path | None = None, progress: ProgressCallback | None = None,
    target: AnyTarget | None = None, lens: str = "pinhole",
) -> StereoCalibration:
    """Calibrate a stereo pair from the image topics of a ROS bag; see :func:`s2r.calib.calibrate_stereo`
    (with ``target``: corner ids and partial views through ``lens``, see
    :mod:`s2r.calib.solve.pipelines.target_stereo`).

    Raises:
        CalibrationError: bag unreadable, a topic missing (the message lists the bag's image topics),
        no pairs within ``max_dt_s``, or the usual calibration input errors.
    """
    bag = Path(bag)
    frames = BagFrames(bag, left_topic, right_topic, rule=SizeRule(error=CalibrationError), grey=True, every=every,
                       max_frames=max_frames, max_dt_s=max_dt_s)
    n_max = frames.message_count() // every
    samples: dict[str, tuple[NDArray[np.uint8], NDArray[np.uint8]]] = {}
    names: list[str] = []

    def items() -> Iterator[DetectItem]:
        for i, (_index, ml, mr) in enumerate(frames.messages()):
            fl = grey_of(ml, error=CalibrationError, bag=bag)
            fr = grey_of(mr, side="right", error=CalibrationError, bag=bag)
            label = f"pair{i:05d}@{ml.stamp_ns * 1e-9:.3f}s"
            names.append(label)
            if len(samples) < _SAMPLES and (not samples or (len(samples) + 1) * 2 * fl.nbytes <= _SAMPLE_BYTES):
                samples[label] = (fl, fr)
            yield DetectItem(name=f"{left_topic}@{ml.stamp_ns * 1e-9:.3f}", sha256=ml.sha256, source=fl)
            yield DetectItem(name=f"{right_topic}@{mr.stamp_ns * 1e-9:.3f}", sha256=mr.sha256, source=fr)

    cache = CornerCache(cache_dir, target) if cache_dir is not None else None
    total = max(1, n_max if max_frames is None else min(n_max, max_frames))
    dets = list(detect_stream(items(), pattern=pattern, jobs=jobs or usable_cores(), cache=cache,
                              total=2 * total, progress=progress, target=target))
    if not names:
        raise CalibrationError(f"no {left_topic} / {right_topic} messages with stamps within {max_dt_s} s",
                               path=bag, field="--max-dt", hint="raise --max-dt or check the topics")
    pairs = [(n, dets[2 * i], dets[2 * i + 1]) for i, n in enumerate(names)]
    if target is not None:
        from s2r.calib.solve.pipelines.target_stereo import calibrate_stereo_target_detections

        result = calibrate_stereo_target_detections(
            pairs, target=target, lens=lens, distortion=distortion, name=name, max_error_px=max_error_px,
            fix_intrinsics=fix_intrinsics, swap=swap, sources=_bag_sources(bag), jobs=jobs or usable_cores())
        sample = next((samples[n] for n in result.used_names if n in samples), None)
        return replace(result, sample_images=sample if sample is None or not swap else (sample[1], sample[0]))
    result = calibrate_stereo_detections(
        pairs, pattern=pattern, square_m=square_m, name=name, distortion=distortion, max_error_px=max_error_px,
        fix_intrinsics=fix_intrinsics, swap=swap, sources=_bag_sources(bag))
    sample = next((samples[n] for n in result.used_names if n in samples), None)
    if sample is not None and swap:
        sample = (sample[1], sample[0])
    return replace(result, sample_images=sample)
