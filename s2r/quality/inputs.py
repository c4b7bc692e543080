"""Inputs of a depth-quality run: image lists from folders or globs, device depth images, paired frames.

Device depth (registered to the left image's pixel grid, e.g. a RealSense D435's depth in its left infrared
camera):

- ``.png`` / ``.tif``: uint16 in ``depth_scale_m`` units (1 mm by default, as realsense-ros and librealsense
  write them), 0 = no data;
- ``.npy``: float32/float64 metres, NaN, inf or <= 0 = no data (uint16 ``.npy`` is read like a PNG).

Folders are listed in sorted name order; left images pair with right images (or depth images) by position,
and the counts must agree.
"""

from __future__ import annotations

import glob
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.errors import DepthError
from s2r.fileio import protect_read_files, read_npy
from s2r.imageio import decode_image_file

__all__ = ["DEPTH_SUFFIXES", "IMAGE_SUFFIXES", "FramePaths", "list_files", "pair_files", "read_depth", "read_grey"]

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".ppm")
DEPTH_SUFFIXES = (".png", ".tif", ".tiff", ".npy")
#: Depth units of 16-bit images: metres per count (realsense-ros and librealsense: 1 mm).
DEFAULT_DEPTH_SCALE_M = 0.001


@dataclass(frozen=True)
class FramePaths:
    """One frame on disk: the left image and either the right image or the device depth image."""

    left: Path
    right: Path | None = None
    depth: Path | None = None


def list_files(spec: str | Path, suffixes: Sequence[str], *, option: str) -> list[Path]:
    """Files of a folder (sorted, filtered by ``suffixes``) or of a glob pattern (sorted); DepthError when none.
    Each is an input of the running command (:func:`s2r.fileio.protect_read_files`)."""
    text = str(spec)
    path = Path(text)
    if path.is_dir():
        files = sorted(p for p in path.iterdir() if p.is_file() and p.suffix.lower() in suffixes)
    elif any(ch in text for ch in "*?["):
        files = sorted(Path(p) for p in glob.glob(text) if Path(p).is_file())
    elif path.is_file():
        files = [path]
    elif path.exists():
        raise DepthError("not a regular file (a device, FIFO or socket): s2r reads files only", path=text,
                         field=option, hint="pass a folder of images or a quoted glob")
    else:
        raise DepthError("no such folder or file", path=text, field=option, hint="pass a folder or a quoted glob")
    if not files:
        raise DepthError(f"no {'/'.join(suffixes)} files found", path=text, field=option,
                         hint="pass a folder of images or a quoted glob such as 'left*.png'")
    protect_read_files(files)  # inputs of the running command: no output may be one of them
    return files


def pair_files(left: Sequence[Path], other: Sequence[Path], *, kind: str) -> list[FramePaths]:
    """Pair left images with right (``kind="right"``) or depth (``kind="depth"``) files by sorted position."""
    if len(left) != len(other):
        raise DepthError(f"{len(left)} left images but {len(other)} {kind} files", field=f"--{kind}",
                         hint=f"give one {kind} file per left image (paired in sorted name order)")
    if kind == "right":
        return [FramePaths(a, right=b) for a, b in zip(left, other, strict=True)]
    return [FramePaths(a, depth=b) for a, b in zip(left, other, strict=True)]


def read_grey(path: Path) -> NDArray[np.uint8]:
    """An image file as 8-bit grey (H, W); 16-bit images (infrared) are scaled by 1/256."""
    image, reason = decode_image_file(path, cv2.IMREAD_UNCHANGED)
    if image is None:
        raise DepthError(reason, path=path, hint="pass PNG/JPEG images")
    if image.dtype == np.uint16:
        image = (np.asarray(image, np.uint16) // 256).astype(np.uint8)
    if image.dtype != np.uint8:
        raise DepthError(f"unsupported pixel type {image.dtype}", path=path, hint="pass 8- or 16-bit images")
    if image.ndim == 3:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2GRAY if image.shape[2] == 4 else cv2.COLOR_BGR2GRAY)
    return np.ascontiguousarray(image, np.uint8)


def depth_from_array(array: NDArray[np.generic], *, scale_m: float, name: str) -> NDArray[np.float32]:
    """Device depth as (H, W) float32 metres with NaN where no data, from uint16 counts or float metres."""
    if array.ndim == 3 and array.shape[2] == 1:
        array = array[:, :, 0]
    if array.ndim != 2:
        raise DepthError(f"expected a single-channel depth image, got shape {array.shape}", path=name,
                         hint="pass uint16 depth PNGs (0 = no data) or float32 metres .npy")
    if array.dtype == np.uint16:
        metres = array.astype(np.float32) * np.float32(scale_m)
        metres[array == 0] = np.nan
        return metres
    if np.issubdtype(array.dtype, np.floating):
        metres = array.astype(np.float32)
        metres[~(np.isfinite(metres) & (metres > 0))] = np.nan
        return metres
    raise DepthError(f"unsupported depth type {array.dtype}", path=name,
                     hint="depth must be uint16 (1 mm units, 0 = no data) or float32 metres")


def read_depth(path: Path, *, scale_m: float = DEFAULT_DEPTH_SCALE_M) -> NDArray[np.float32]:
    """A device depth file (see the module docstring) as (H, W) float32 metres, NaN = no data."""
    array: NDArray[np.generic] | None
    if path.suffix.lower() == ".npy":
        try:
            array = read_npy(path)
        except FileNotFoundError:
            raise DepthError("file not found", path=path, hint="check the path") from None
        except (OSError, ValueError) as exc:  # NotARegularFile is a ValueError
            raise DepthError(f"not a readable .npy array: {exc}", path=path,
                             hint="save (H, W) float32 metres with numpy.save") from None
    else:
        array, reason = decode_image_file(path, cv2.IMREAD_UNCHANGED)
        if array is None:
            raise DepthError(f"not a readable depth image: {reason}", path=path, hint="pass uint16 PNG depth images")
        if array.dtype == np.uint8:
            raise DepthError("8-bit image: a depth image must be uint16 (1 mm units)", path=path,
                             hint="pass the raw 16-bit depth PNG, not a colourised view")
    return depth_from_array(array, scale_m=scale_m, name=str(path))
