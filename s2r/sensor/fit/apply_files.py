"""``s2r sensor apply``: a sensor model on depth files (a simulator's perfect depth) -> the device's depth files.

Inputs are read as ``depth-quality`` reads device depth (:func:`s2r.quality.inputs.read_depth`): uint16 PNG/TIFF
in ``depth_scale_m`` units (0 = no data) or float ``.npy`` metres. Each output keeps its input's name and kind:
PNG/TIFF in -> uint16 PNG/TIFF in the same units (0 = no data), ``.npy`` in -> float32 metres (NaN = no data).
Frame ``k`` (sorted order) is seeded by ``(seed, k)``. The outputs are published whole, through s2r's one
output policy (:class:`s2r.fileio.OutputBatch`): every file is staged beside its name, then all are moved into
place, or none (a full disk leaves nothing half-written).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.errors import DepthError
from s2r.fileio import OutputBatch, npy_bytes, prepare_output_dir
from s2r.quality.inputs import read_depth
from s2r.sensor.depth import degrade_depth
from s2r.sensor.model import SensorModel

__all__ = ["apply_to_files", "encode_depth"]


def encode_depth(depth_m: NDArray[np.float32], suffix: str, *, scale_m: float) -> bytes:
    """(H, W) metres (NaN no data) as a uint16 image file's bytes (``suffix`` .png or .tif), 0 = no data."""
    counts = np.where(np.isfinite(depth_m), np.round(np.nan_to_num(depth_m) / scale_m), 0)
    ok, buf = cv2.imencode(suffix, np.clip(counts, 0, 65535).astype(np.uint16))
    if not ok:
        raise DepthError("cannot encode the depth image", field="-o", hint="write .png, .tif or .npy depth")
    return bytes(buf.tobytes())


def _encoded(src: Path, depth: NDArray[np.float32], *, scale_m: float) -> bytes:
    """The output file's bytes: float32 ``.npy`` metres for a ``.npy`` input, else a uint16 image."""
    if src.suffix.lower() == ".npy":
        return npy_bytes(depth.astype(np.float32))
    return encode_depth(depth, src.suffix.lower(), scale_m=scale_m)


def apply_to_files(model: SensorModel, sources: Sequence[Path], out_dir: str | Path, *, fb_px_m: float,
                   seed: int = 0, depth_scale_m: float = 0.001, force: bool = False) -> list[Path]:
    """Degrade every depth file of ``sources`` (:func:`s2r.sensor.degrade_depth`) into ``out_dir`` (module
    docstring); returns the written paths."""
    names = [s.name for s in sources]
    if len(set(names)) != len(names):
        raise DepthError("two inputs share a file name", field="DEPTH", hint="apply one folder at a time")
    out = prepare_output_dir(out_dir, force=force)
    with OutputBatch(force=force, root=out) as batch:
        for k, src in enumerate(sources):
            depth = degrade_depth(read_depth(src, scale_m=depth_scale_m), model, fb_px_m=fb_px_m,
                                  rng=np.random.default_rng([seed, k]))
            batch.add_bytes(out / src.name, _encoded(src, depth, scale_m=depth_scale_m))
        return batch.publish()
