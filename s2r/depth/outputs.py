"""Reading stereo images and writing depth outputs (atomic writes through :mod:`s2r.fileio`).

File conventions:

- ``disparity.npy``: (H, W) float32 pixels in the rectified left image, NaN invalid.
- ``depth.png``: (H, W) uint16 millimetres along the rectified left optical axis, 0 = invalid (the ROS /
  RealSense ``16UC1`` convention); depths beyond 65.535 m clip to 65535.
- ``depth_color.png``: the disparity through OpenCV's JET colour map (near red, far blue), invalid black, with a
  colour bar on the right labelled in metres (near at the top, far at the bottom).
- ``points.ply``: binary little-endian PLY, float32 x y z metres in the rectified left optical frame and uchar
  red green blue; ``.pcd``: binary PCD v0.7 of the same points (x y z float32, rgb packed as PCL does).
- ``camera_info.yaml``: ROS camera_info (camera_calibration_parsers YAML) of the RECTIFIED left camera, the frame
  of every output above: K and P from the rectified projection P1, R identity, zero distortion, the image size.

Depth outside the profile's working range (``matcher.min_depth_m`` .. ``max_depth_m``) is invalid by default
(:func:`limit_depth_range`): a matcher's far end is noise (76 m points from a 1-px disparity).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.depth.pipeline import DepthResult
from s2r.errors import DepthError
from s2r.fileio import OutputBatch, atomic_write_bytes, atomic_write_npy, atomic_write_text, npy_bytes
from s2r.formats.ros import RosCameraInfo, camera_info_to_yaml
from s2r.imageio import decode_image_file
from s2r.rectification import StereoRectification

__all__ = [
    "IMAGE_SUFFIXES",
    "depth_colour_with_bar",
    "depth_to_mm",
    "disparity_colour",
    "limit_depth_range",
    "pcd_bytes",
    "ply_bytes",
    "png_bytes",
    "read_image",
    "rectified_camera_info",
    "write_camera_info",
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
    image, reason = decode_image_file(path, cv2.IMREAD_UNCHANGED)
    if image is None:
        raise DepthError(f"cannot read image: {reason}", path=path, hint="pass a PNG/JPEG/BMP/TIFF/PGM image")
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


def disparity_colour(disparity: NDArray[np.floating], limits: tuple[float, float] | None = None
                     ) -> NDArray[np.uint8]:
    """(H, W, 3) BGR JET rendering of a disparity map, scaled over ``limits`` (low, high disparity px; default its
    valid range; values beyond are clipped to the end colours); invalid pixels black."""
    valid = np.isfinite(disparity)
    if not valid.any():
        return np.zeros((*disparity.shape, 3), np.uint8)
    lo, hi = limits if limits is not None else (float(np.min(disparity[valid])), float(np.max(disparity[valid])))
    scaled = (np.where(valid, disparity, lo) - lo) * (255.0 / max(hi - lo, 1e-6))
    colour = cv2.applyColorMap(np.clip(scaled, 0, 255).astype(np.uint8), cv2.COLORMAP_JET)
    colour[~valid] = 0
    return np.asarray(colour, np.uint8)


def _depth_of_disparity(Q: NDArray[np.float64], disparity: float) -> float:
    """Depth (metres) of a disparity (pixels) through the reprojection matrix: ``Z = Q[2,3] / (Q[3,2] d + Q[3,3])``."""
    w = float(Q[3, 2]) * disparity + float(Q[3, 3])
    return float(Q[2, 3]) / w if w > 0 else float("inf")


def _colour_bar(height: int, lo: float, hi: float, Q: NDArray[np.float64], *, width: int = 110) -> NDArray[np.uint8]:
    """A (height, width, 3) panel: the JET bar (high disparity = near at the top) with depth labels in metres."""
    panel = np.full((height, width, 3), 255, np.uint8)
    top, bottom = 24, height - 24
    ramp = np.linspace(255, 0, max(bottom - top, 2)).astype(np.uint8)[:, None]
    bar = cv2.applyColorMap(np.repeat(ramp, 18, axis=1), cv2.COLORMAP_JET)
    panel[top:top + bar.shape[0], 8:26] = bar
    font, scale = cv2.FONT_HERSHEY_SIMPLEX, 0.4
    cv2.putText(panel, "near", (30, 12), font, scale, (0, 0, 0), 1, cv2.LINE_AA)
    cv2.putText(panel, "far", (30, height - 6), font, scale, (0, 0, 0), 1, cv2.LINE_AA)
    ticks = 5 if bar.shape[0] >= 120 else 2
    for i in range(ticks):
        frac = i / (ticks - 1)
        y = round(top + frac * (bar.shape[0] - 1))
        z = _depth_of_disparity(Q, hi - frac * (hi - lo))
        cv2.line(panel, (26, y), (32, y), (0, 0, 0), 1)
        cv2.putText(panel, f"{z:.2f} m", (35, y + 4), font, scale, (0, 0, 0), 1, cv2.LINE_AA)
    return panel


def _disparity_of_depth(Q: NDArray[np.float64], depth_m: float) -> float:
    """Disparity (pixels) of a depth (metres), the inverse of :func:`_depth_of_disparity`."""
    return (float(Q[2, 3]) / depth_m - float(Q[3, 3])) / float(Q[3, 2])


def depth_colour_with_bar(disparity: NDArray[np.floating], Q: NDArray[np.float64],
                          colour_range_m: tuple[float, float] | None = None) -> NDArray[np.uint8]:
    """:func:`disparity_colour` with a colour bar on the right giving the near and far depth in metres (via ``Q``).

    ``colour_range_m`` ``(near, far)``: a fixed colour scale (the same colour means the same depth in every frame
    of a sequence); default each map's own valid range.
    """
    valid = np.isfinite(disparity)
    if colour_range_m is not None:
        lo, hi = _disparity_of_depth(Q, colour_range_m[1]), _disparity_of_depth(Q, colour_range_m[0])
    elif valid.any():
        lo, hi = float(np.min(disparity[valid])), float(np.max(disparity[valid]))
    else:
        return disparity_colour(disparity)
    image = disparity_colour(disparity, (lo, hi))
    return np.ascontiguousarray(np.hstack([image, _colour_bar(image.shape[0], lo, hi, Q)]))


def limit_depth_range(result: DepthResult, near_m: float, far_m: float) -> tuple[DepthResult, int]:
    """``result`` with depths outside ``[near_m, far_m]`` made invalid (NaN depth and disparity, valid False).

    Returns the new result and the number of pixels removed. Depth is along the rectified left optical axis.
    """
    with np.errstate(invalid="ignore"):
        outside = result.valid & ((result.depth < near_m) | (result.depth > far_m))
    removed = int(np.count_nonzero(outside))
    if not removed:
        return result, 0
    depth, disparity = result.depth.copy(), result.disparity.copy()
    depth[outside] = np.nan
    disparity[outside] = np.nan
    return replace(result, depth=depth, disparity=disparity, valid=result.valid & ~outside), removed


def rectified_camera_info(rect: StereoRectification, *, name: str = "rectified_left") -> RosCameraInfo:
    """The ROS camera_info of the rectified left camera: ``K = P1[:, :3]``, ``P = P1``, R identity, no distortion."""
    width, height = rect.image_size
    return RosCameraInfo(camera_name=name, width=int(width), height=int(height), K=np.array(rect.P1[:, :3]),
                         D=np.zeros(5), distortion_model="plumb_bob", R=np.eye(3), P=np.array(rect.P1))


def write_camera_info(path: str | Path, rect: StereoRectification, *, name: str = "rectified_left",
                      force: bool = False, batch: OutputBatch | None = None) -> Path:
    """Write :func:`rectified_camera_info` as camera_calibration_parsers YAML (atomic; staged in ``batch``, to
    be published with the files beside it, when given)."""
    text = camera_info_to_yaml(rectified_camera_info(rect, name=name))
    if batch is not None:
        return batch.add_text(path, text)
    return atomic_write_text(path, text, force=force)


def png_bytes(image: NDArray[np.uint8] | NDArray[np.uint16], path: Path) -> bytes:
    """``image`` (8- or 16-bit) as PNG bytes; DepthError naming ``path`` when OpenCV cannot encode it."""
    ok, buf = cv2.imencode(".png", image)
    if not ok:
        raise DepthError("PNG encoding failed", path=path)
    return bytes(buf.tobytes())


def write_depth_png(path: str | Path, depth_m: NDArray[np.floating], *, force: bool = False) -> Path:
    """Write depth (metres, NaN invalid) as a uint16 millimetre PNG, 0 invalid."""
    path = Path(path)
    return atomic_write_bytes(path, png_bytes(depth_to_mm(depth_m), path), force=force)


def write_disparity(path: str | Path, disparity: NDArray[np.floating], *, force: bool = False) -> Path:
    """Write the float32 disparity (pixels, NaN invalid) as a .npy file."""
    return atomic_write_npy(path, np.asarray(disparity, dtype=np.float32), force=force)


def write_ply(path: str | Path, points: NDArray[np.float32], colours: NDArray[np.uint8], *, force: bool = False
              ) -> Path:
    """Write (N, 3) points (metres) with (N, 3) RGB colours as a binary little-endian PLY."""
    return atomic_write_bytes(path, ply_bytes(points, colours), force=force)


def ply_bytes(points: NDArray[np.float32], colours: NDArray[np.uint8]) -> bytes:
    """(N, 3) points (metres) with (N, 3) RGB colours as the bytes of a binary little-endian PLY."""
    n = int(points.shape[0])
    header = (f"ply\nformat binary_little_endian 1.0\ncomment s2r depth point cloud, metres, rectified left "
              f"optical frame\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\n"
              "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n")
    rows = np.empty(n, dtype=[("xyz", "<f4", (3,)), ("rgb", "u1", (3,))])
    rows["xyz"], rows["rgb"] = points, colours
    return header.encode("ascii") + rows.tobytes()


def pcd_bytes(points: NDArray[np.float32], colours: NDArray[np.uint8]) -> bytes:
    """(N, 3) points (metres) with (N, 3) RGB colours as the bytes of a binary PCD v0.7 (PCL's layout: x y z
    float32 and rgb as the float32 whose bits are 0x00RRGGBB)."""
    n = int(points.shape[0])
    header = ("# .PCD v0.7 - s2r depth point cloud, metres, rectified left optical frame\nVERSION 0.7\n"
              "FIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
              f"WIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA binary\n")
    rgb = np.asarray(colours, np.uint32)
    packed = ((rgb[:, 0] << 16) | (rgb[:, 1] << 8) | rgb[:, 2]).astype("<u4")
    rows = np.empty(n, dtype=[("xyz", "<f4", (3,)), ("rgb", "<u4")])
    rows["xyz"], rows["rgb"] = points, packed
    return header.encode("ascii") + rows.tobytes()


def write_outputs(folder: str | Path, result: DepthResult, *, prefix: str = "", ply: bool = False,
                  force: bool = False, depth_range_m: tuple[float, float] | None = None,
                  batch: OutputBatch | None = None, colour_range_m: tuple[float, float] | None = None) -> list[Path]:
    """Write ``{prefix}disparity.npy``, ``depth.png``, ``depth_color.png`` (and ``points.ply``) into ``folder``,
    published together or not at all (staged in ``batch`` when given: a sequence publishes every frame at once).

    ``depth_range_m`` ``(near, far)``: depths outside it are written as invalid (see :func:`limit_depth_range`).
    ``colour_range_m`` ``(near, far)``: the fixed colour scale of ``depth_color.png`` (default: each map's own).
    """
    folder = Path(folder)
    if batch is None:
        with OutputBatch(force=force, root=folder) as own:
            written = write_outputs(folder, result, prefix=prefix, ply=ply, depth_range_m=depth_range_m, batch=own,
                                    colour_range_m=colour_range_m)
            own.publish()
        return written
    if depth_range_m is not None:
        result, _ = limit_depth_range(result, *depth_range_m)
    colour_path = folder / f"{prefix}depth_color.png"
    depth_path = folder / f"{prefix}depth.png"
    written = [
        batch.add_bytes(folder / f"{prefix}disparity.npy", npy_bytes(np.asarray(result.disparity, np.float32))),
        batch.add_bytes(depth_path, png_bytes(depth_to_mm(result.depth), depth_path)),
        batch.add_bytes(colour_path, png_bytes(depth_colour_with_bar(result.disparity, result.Q, colour_range_m),
                                               colour_path)),
    ]
    if ply:
        written.append(batch.add_bytes(folder / f"{prefix}points.ply", ply_bytes(*result.point_cloud())))
    return written
