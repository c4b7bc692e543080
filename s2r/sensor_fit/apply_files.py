"""``s2r sensor apply``: a sensor model on depth files (a simulator's perfect depth) -> the device's depth files.

Inputs are read as ``depth-quality`` reads device depth (:func:`s2r.quality.inputs.read_depth`): uint16 PNG/TIFF
in ``depth_scale_m`` units (0 = no data) or float ``.npy`` metres. Each output keeps its input's name and kind:
PNG/TIFF in -> uint16 PNG/TIFF in the same units (0 = no data), ``.npy`` in -> float32 metres (NaN = no data).
Frame ``k`` (sorted order) is seeded by ``(seed, k)``. The output folder is published whole: the files are
written into a temporary sibling folder that is renamed into place, unless ``force`` reuses an existing folder
(then each file is replaced atomically).
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.errors import DepthError
from s2r.fileio import atomic_write_bytes, atomic_write_npy, check_output_dir
from s2r.quality.inputs import read_depth
from s2r.sensor.depth import degrade_depth
from s2r.sensor_model import SensorModel

__all__ = ["apply_to_files", "encode_depth"]


def encode_depth(depth_m: NDArray[np.float32], suffix: str, *, scale_m: float) -> bytes:
    """(H, W) metres (NaN no data) as a uint16 image file's bytes (``suffix`` .png or .tif), 0 = no data."""
    counts = np.where(np.isfinite(depth_m), np.round(np.nan_to_num(depth_m) / scale_m), 0)
    ok, buf = cv2.imencode(suffix, np.clip(counts, 0, 65535).astype(np.uint16))
    if not ok:
        raise DepthError("cannot encode the depth image", field="-o", hint="write .png, .tif or .npy depth")
    return bytes(buf.tobytes())


def _write(out: Path, src: Path, depth: NDArray[np.float32], *, scale_m: float, force: bool) -> Path:
    target = out / src.name
    if src.suffix.lower() == ".npy":
        return atomic_write_npy(target, depth.astype(np.float32), force=force)
    return atomic_write_bytes(target, encode_depth(depth, src.suffix.lower(), scale_m=scale_m), force=force)


def apply_to_files(model: SensorModel, sources: Sequence[Path], out_dir: str | Path, *, fb_px_m: float,
                   seed: int = 0, depth_scale_m: float = 0.001, force: bool = False) -> list[Path]:
    """Degrade every depth file of ``sources`` (:func:`s2r.sensor.degrade_depth`) into ``out_dir`` (module
    docstring); returns the written paths."""
    out = check_output_dir(out_dir, force=force)
    names = [s.name for s in sources]
    if len(set(names)) != len(names):
        raise DepthError("two inputs share a file name", field="DEPTH", hint="apply one folder at a time")
    reuse = force and out.is_dir()
    if not reuse:
        out.parent.mkdir(parents=True, exist_ok=True)
    target = out if reuse else Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    try:
        written = []
        for k, src in enumerate(sources):
            depth = degrade_depth(read_depth(src, scale_m=depth_scale_m), model, fb_px_m=fb_px_m,
                                  rng=np.random.default_rng([seed, k]))
            written.append(_write(target, src, depth, scale_m=depth_scale_m, force=reuse))
        if not reuse:
            if out.is_dir():
                out.rmdir()  # empty (check_output_dir refused a full one)
            os.replace(target, out)
            written = [out / p.name for p in written]
    except BaseException:
        if not reuse:
            shutil.rmtree(target, ignore_errors=True)
        raise
    return written
