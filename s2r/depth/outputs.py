"""Reading stereo images and writing depth outputs (atomic writes through :mod:`s2r.fileio`).

File conventions:

- ``disparity.npy``: (H, W) float32 pixels in the rectified left image, NaN invalid.
- ``depth.png``: (H, W) uint16 millimetres along the rectified left optical axis, 0 = invalid (the ROS /
  RealSense ``16UC1`` convention); depths beyond 65.535 m clip to 65535.
- ``depth_color.png``: the disparity through OpenCV's JET colour map (near red, far blue), invalid black.
- ``points.ply``: binary little-endian PLY, float32 x y z metres in the rectified left optical frame and uchar
  red green blue.
"""

from __future__ import annotations

import logging
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.depth.pipeline import DepthResult
from s2r.errors import DepthError
from s2r.fileio import atomic_write_bytes, atomic_write_npy, native_stderr_captured

__all__ = [
    "IMAGE_SUFFIXES",
    "depth_to_mm",
    "disparity_colour",
    "read_image",
    "write_depth_png",
    "write_disparity",
    "write_outputs",
    "write_ply",
]

#: File suffixes ``read_image`` and the sequence mode accept.
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".ppm", ".webp")


def read_image(path: str | Path) -> NDArray[np.uint8]:
    """An 8-bit image as (H, W) grey or (H, W, 3) BGR; :class:`DepthError` naming the file otherwise."""
    path = Path(path)
    if not path.is_file():
        raise DepthError("image file not found", path=path, hint="check the path")
    data = np.fromfile(path, dtype=np.uint8)
    with native_stderr_captured() as decoder_notes:  # no bare libjpeg/libpng lines on stderr
        image = cv2.imdecode(data, cv2.IMREAD_UNCHANGED) if data.size else None
    if decoder_notes and image is not None:
        logging.getLogger(__name__).warning("%s: the image decoder reported %r; the image may be damaged", path,
                       "; ".join(decoder_notes)[:200])
    if image is None:
        raise DepthError("cannot read image (not an image file, or corrupt)", path=path,
                         hint="pass a PNG/JPEG/BMP/TIFF/PGM image")
    if image.dtype != np.uint8:
        raise DepthError(f"image has {image.dtype} pixels; the matcher needs 8-bit", path=path,
                         hint="convert it to 8-bit grey or colour")
    if image.ndim == 3 and image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    return np.asarray(image, np.uint8)


def depth_to_mm(depth_m: NDArray[np.floating]) -> NDArray[np.uint16]:
    """Depth in metres (NaN invalid) -> uint16 millimetres, rounded, 0 invalid, clipped to 1..65535."""
    mm = np.rint(np.asarray(depth_m, dtype=np.float64) * 1000.0)
    valid = np.isfinite(mm) & (mm > 0)
    return np.where(valid, np.clip(np.where(valid, mm, 0), 1, 65535), 0).astype(np.uint16)


def disparity_colour(disparity: NDArray[np.floating]) -> NDArray[np.uint8]:
    """(H, W, 3) BGR JET rendering of a disparity map, scaled over its valid range; invalid pixels black."""
    valid = np.isfinite(disparity)
    if not valid.any():
        return np.zeros((*disparity.shape, 3), np.uint8)
    lo, hi = float(np.min(disparity[valid])), float(np.max(disparity[valid]))
    scaled = (np.where(valid, disparity, lo) - lo) * (255.0 / max(hi - lo, 1e-6))
    colour = cv2.applyColorMap(np.clip(scaled, 0, 255).astype(np.uint8), cv2.COLORMAP_JET)
    colour[~valid] = 0
    return np.asarray(colour, np.uint8)


def _png_bytes(image: NDArray[np.uint8] | NDArray[np.uint16], path: Path) -> bytes:
    ok, buf = cv2.imencode(".png", image)
    if not ok:
        raise DepthError("PNG encoding failed", path=path)
    return bytes(buf.tobytes())


def write_depth_png(path: str | Path, depth_m: NDArray[np.floating], *, force: bool = False) -> Path:
    """Write depth (metres, NaN invalid) as a uint16 millimetre PNG, 0 invalid."""
    path = Path(path)
    return atomic_write_bytes(path, _png_bytes(depth_to_mm(depth_m), path), force=force)


def write_disparity(path: str | Path, disparity: NDArray[np.floating], *, force: bool = False) -> Path:
    """Write the float32 disparity (pixels, NaN invalid) as a .npy file."""
    return atomic_write_npy(path, np.asarray(disparity, dtype=np.float32), force=force)


def write_ply(path: str | Path, points: NDArray[np.float32], colours: NDArray[np.uint8], *, force: bool = False
              ) -> Path:
    """Write (N, 3) points (metres) with (N, 3) RGB colours as a binary little-endian PLY."""
    n = int(points.shape[0])
    header = (f"ply\nformat binary_little_endian 1.0\ncomment s2r depth point cloud, metres, rectified left "
              f"optical frame\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\n"
              "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n")
    rows = np.empty(n, dtype=[("xyz", "<f4", (3,)), ("rgb", "u1", (3,))])
    rows["xyz"], rows["rgb"] = points, colours
    return atomic_write_bytes(path, header.encode("ascii") + rows.tobytes(), force=force)


def write_outputs(folder: str | Path, result: DepthResult, *, prefix: str = "", ply: bool = False,
                  force: bool = False) -> list[Path]:
    """Write ``{prefix}disparity.npy``, ``depth.png``, ``depth_color.png`` (and ``points.ply``) into ``folder``."""
    folder = Path(folder)
    colour_path = folder / f"{prefix}depth_color.png"
    written = [
        write_disparity(folder / f"{prefix}disparity.npy", result.disparity, force=force),
        write_depth_png(folder / f"{prefix}depth.png", result.depth, force=force),
        atomic_write_bytes(colour_path, _png_bytes(disparity_colour(result.disparity), colour_path), force=force),
    ]
    if ply:
        written.append(write_ply(folder / f"{prefix}points.ply", *result.point_cloud(), force=force))
    return written
