"""OpenCV FileStorage (YAML or XML) as OpenCV's stereo_calib sample writes it.

Read by s2r's safe reader (formats/filestorage.py, never cv2.FileStorage); written by cv2.FileStorage.

Nodes: ``M1 D1 M2 D2`` (camera matrices and distortion), ``R T`` (OpenCV extrinsics,
``X_right = R X_left + T``), optionally ``R1 R2 P1 P2 Q`` (rectification; ignored on import, recomputed
on export). The sample writes ``intrinsics.yml`` (M1 D1 M2 D2) and ``extrinsics.yml`` (R T R1 R2 P1 P2 Q)
and no image size: pass both files, and the image size when neither file holds ``image_width`` /
``image_height`` (or ``size: [W, H]`` / ``imageSize``).

Units: ``T`` is in whatever unit the board's square size was given in. The sample calibrates with a
square size of 1 unless told otherwise, so its T is in SQUARES: pass ``t_scale_m`` (CLI ``--units-m``)
= the square size in metres (e.g. 0.025) to get metres.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.errors import FormatError
from s2r.fileio import atomic_write_text
from s2r.formats._common import (
    MAX_ABS_VALUE,
    as_int,
    as_matrix,
    build_camera,
    build_stereo,
    distortion_for,
    provenance_for,
    rotation_as_printed,
)
from s2r.formats.filestorage import read_filestorage
from s2r.formats.slam_settings import flavour_of, load_settings
from s2r.profile import MAX_BASELINE_M, Camera, Distortion, MonoProfile, StereoProfile
from s2r.rectification import stereo_rectification

__all__ = [
    "OpenCVStereo", "dump_opencv", "load_opencv", "mono_opencv_text", "opencv_to_text", "read_filestorage_nodes",
    "read_opencv_stereo",
]

log = logging.getLogger(__name__)
FloatArray = NDArray[np.float64]
NodeValue = FloatArray | str | float | dict[str, Any]
#: Matrix nodes of OpenCV's stereo sample and their shapes (None: any shape, checked later).
_MATRIX_SHAPES: dict[str, tuple[int, int] | None] = {
    "M1": (3, 3), "M2": (3, 3), "D1": None, "D2": None, "R": None, "T": None,
    "R1": (3, 3), "R2": (3, 3), "P1": (3, 4), "P2": (3, 4), "Q": (4, 4),
}


@dataclass(frozen=True, eq=False)
class OpenCVStereo:
    """The nodes of OpenCV stereo calibration file(s): K (3x3, pixels), D vectors, optional R (3x3), T (3,)."""

    M1: FloatArray
    D1: FloatArray
    M2: FloatArray
    D2: FloatArray
    R: FloatArray | None
    T: FloatArray | None
    image_size: tuple[int, int] | None
    distortion_model: str | None
    paths: tuple[Path, ...]
    rectified: tuple[FloatArray, FloatArray] | None = None


#: Other names the same stereo nodes go by (OpenCV's stereoCalibrate argument names, tutorials' K1 D1 K2 D2).
_ALIASES: dict[str, tuple[str, ...]] = {
    "M1": ("K1", "cameraMatrix1", "CM1", "camera_matrix_left", "cameraMatrixLeft", "cameraMatrixL", "K_left", "KL",
           "left_camera_matrix", "mtxL", "mtx_left"),
    "M2": ("K2", "cameraMatrix2", "CM2", "camera_matrix_right", "cameraMatrixRight", "cameraMatrixR", "K_right", "KR",
           "right_camera_matrix", "mtxR", "mtx_right"),
    "D1": ("distCoeffs1", "dist_coeffs_left", "distCoeffsLeft", "distCoeffsL", "D_left", "DL", "left_distortion",
           "distL", "dist_left"),
    "D2": ("distCoeffs2", "dist_coeffs_right", "distCoeffsRight", "distCoeffsR", "D_right", "DR", "right_distortion",
           "distR", "dist_right"),
}


def _with_aliases(nodes: dict[str, NodeValue | None]) -> dict[str, NodeValue | None]:
    out = dict(nodes)
    for canonical, names in _ALIASES.items():
        found = next((n for n in names if n in nodes), None)
        if canonical not in out and found is not None:
            out[canonical] = nodes[found]
    return out


def read_filestorage_nodes(path: Path) -> dict[str, Any]:
    """Every top-level node of an OpenCV FileStorage file (matrices as float64 arrays, maps as dicts)."""
    return _read_nodes(path)


def _read_nodes(path: Path) -> dict[str, NodeValue | None]:
    """Every top-level node of a FileStorage file, read by s2r's safe reader (never cv2.FileStorage, which
    corrupts memory on some malformed files), with the stereo nodes' other names mapped; a bad file becomes a
    one-line FormatError."""
    nodes = _with_aliases(read_filestorage(path))
    _check_matrix_nodes(nodes, path)
    return nodes


def _check_matrix_nodes(nodes: dict[str, NodeValue | None], path: Path) -> None:
    """Every stereo node present must be a whole matrix of its shape (a cut-off file leaves a stub)."""
    for key, shape in _MATRIX_SHAPES.items():
        if key not in nodes:
            continue
        value = nodes[key]
        if not isinstance(value, np.ndarray) or value.size == 0:
            raise FormatError("incomplete or not a matrix (truncated file?)", path=path, field=key,
                              hint="re-export the file from OpenCV")
        if shape is not None and value.shape != shape:
            raise FormatError(f"expected a {shape[0]}x{shape[1]} matrix, got {value.shape[0]}x{value.shape[1]}",
                              path=path, field=key)


def _array(nodes: dict[str, NodeValue | None], key: str, path: Path) -> FloatArray | None:
    value = nodes.get(key)
    if value is None:
        return None
    if not isinstance(value, np.ndarray):
        raise FormatError("expected a matrix", path=path, field=key)
    if not np.all(np.isfinite(value)):
        raise FormatError("must hold finite numbers only (found NaN or inf)", path=path, field=key)
    if value.size and float(np.max(np.abs(value))) > MAX_ABS_VALUE:
        raise FormatError(f"holds {float(np.max(np.abs(value))):g}, beyond {MAX_ABS_VALUE:g} in magnitude: no "
                          "calibration value is that large (corrupted file or wrong units?)", path=path, field=key)
    return value


def _image_size(nodes: dict[str, NodeValue | None], path: Path) -> tuple[int, int] | None:
    for wkey, hkey in (("image_width", "image_height"), ("width", "height")):
        if wkey in nodes and hkey in nodes:
            return as_int(nodes[wkey], path, wkey), as_int(nodes[hkey], path, hkey)
    for key in ("imageSize", "image_size", "size"):  # [width, height], as OpenCV's stereo_calib and users write it
        value = nodes.get(key)
        if isinstance(value, np.ndarray):
            size = as_matrix(value.tolist(), (2,), path, key)
            return as_int(size[0], path, key), as_int(size[1], path, key)
    return None


def read_opencv_stereo(paths: str | Path | Sequence[str | Path]) -> OpenCVStereo:
    """Read M1 D1 M2 D2 (and R T when present) from one file or a pair (intrinsics + extrinsics).

    A node found in an earlier file wins over the same node in a later one.
    """
    files = [Path(paths)] if isinstance(paths, (str, Path)) else [Path(p) for p in paths]
    merged: dict[str, tuple[NodeValue | None, Path]] = {}
    for path in files:
        for key, value in _read_nodes(path).items():
            merged.setdefault(key, (value, path))
    nodes = {k: v for k, (v, _) in merged.items()}

    def where(key: str) -> Path:
        return merged[key][1] if key in merged else files[0]

    calibration_keys = {"M1", "M2", "D1", "D2", "R", "T", "R1", "R2", "P1", "P2", "Q", "camera_matrix"}
    if not calibration_keys & set(nodes):
        found = ", ".join(sorted(nodes)[:8]) or "nothing"
        raise FormatError(f"unrecognised OpenCV FileStorage: no stereo calibration in it (keys: {found})",
                          path=files[0], hint="expected OpenCV stereo_calib (M1 D1 M2 D2 R T), ORB-SLAM, "
                          "VINS-Fusion or Kimera-VIO stereo settings")
    if "camera_matrix" in nodes and "M1" not in nodes:
        raise FormatError("holds one camera (camera_matrix, distortion_coefficients): a stereo profile needs two",
                          path=files[0], field="camera_matrix", hint="pass the stereo calibration file(s)")
    required = {}
    for key in ("M1", "D1", "M2", "D2"):
        value = _array(nodes, key, where(key))
        if value is None:
            found = ", ".join(sorted(nodes)[:8]) or "nothing"
            raise FormatError(f"required matrix is missing: OpenCV stereo files hold M1 D1 M2 D2 (or K1 D1 K2 D2); "
                              f"this file has {found}", path=where(key), field=key,
                              hint="pass the intrinsics file (M1 D1 M2 D2) together with the extrinsics file")
        required[key] = value
    for key in ("M1", "M2"):
        required[key] = as_matrix(required[key].tolist(), (3, 3), where(key), key)
    for key in ("D1", "D2"):
        required[key] = required[key].reshape(-1)
    model = nodes.get("distortion_model")
    return OpenCVStereo(
        M1=required["M1"], D1=required["D1"], M2=required["M2"], D2=required["D2"],
        R=_rotation(nodes, where("R")), T=_translation(nodes, where("T")), rectified=_rectified(nodes, where("P2")),
        image_size=_image_size(nodes, where("image_width")), distortion_model=model if isinstance(model, str) else None,
        paths=tuple(files),
    )


def _rotation(nodes: dict[str, NodeValue | None], path: Path) -> FloatArray | None:
    value = _array(nodes, "R", path)
    if value is None:
        return None
    if value.size == 3:  # a Rodrigues rotation vector
        value = np.asarray(cv2.Rodrigues(value.reshape(3, 1))[0], dtype=np.float64)
    return rotation_as_printed(as_matrix(value.tolist(), (3, 3), path, "R"), path, "R")


def _rectified(nodes: dict[str, NodeValue | None], path: Path) -> tuple[FloatArray, FloatArray] | None:
    """``(R, T)`` from a factory calibration's ``R1 P1 R2 P2`` alone (MultiSense): as from ROS camera_info,
    ``R = R2^T R1``, ``T = R2^T (t2 - t1)`` with ``t = K'^-1 P[:, 3]`` (P's Tx in metres)."""
    if not all(isinstance(nodes.get(k), np.ndarray) for k in ("R1", "R2", "P1", "P2")):
        return None
    arrays = {k: _array(nodes, k, path) for k in ("R1", "R2", "P1", "P2")}
    R1, R2 = (rotation_as_printed(np.asarray(arrays[k]), path, k) for k in ("R1", "R2"))
    offsets = []
    for key in ("P1", "P2"):
        P = np.asarray(arrays[key])
        if abs(float(np.linalg.det(P[:, :3]))) < 1e-12:
            raise FormatError("left 3x3 block of P is singular", path=path, field=key)
        offsets.append(np.linalg.solve(P[:, :3], P[:, 3]))
    return R2.T @ R1, R2.T @ (offsets[1] - offsets[0])


def _translation(nodes: dict[str, NodeValue | None], path: Path) -> FloatArray | None:
    value = _array(nodes, "T", path)
    return None if value is None else as_matrix(value.reshape(-1).tolist(), (3,), path, "T")


def _distortion(coeffs: FloatArray, model: str | None, path: Path, field: str) -> Distortion:
    values = [float(v) for v in coeffs]
    if model in ("equidistant", "fisheye"):
        return distortion_for("equidistant", values, path, field)
    if len(values) in (12, 14) and not any(values[8:]):
        values = values[:8]  # OpenCV's thin-prism / tilt terms, all zero: the rational model
    if len(values) == 4:
        values = [*values, 0.0]  # k1 k2 p1 p2 without k3
    if len(values) == 8 and not any(values[5:]):
        values = values[:5]  # the rational model with k4 = k5 = k6 = 0 (MultiSense factory files): plumb_bob
    counts = {5: "plumb_bob", 8: "rational_polynomial"}
    if len(values) not in counts:
        raise FormatError(f"expected 4, 5 or 8 distortion coefficients, got {len(values)}", path=path, field=field,
                          hint="thin-prism and tilt terms (12/14 coefficients) are not supported unless zero")
    return distortion_for(counts[len(values)], values, path, field)


def _camera(data: OpenCVStereo, side: int, size: tuple[int, int]) -> Camera:
    K, D = (data.M1, data.D1) if side == 1 else (data.M2, data.D2)
    path = data.paths[0]
    distortion = _distortion(D, data.distortion_model, path, f"D{side}")
    return build_camera(K=K, size=size, distortion=distortion, path=path, field=f"M{side}")


def load_opencv(
    paths: str | Path | Sequence[str | Path],
    *,
    image_size: tuple[int, int] | None = None,
    t_scale_m: float = 1.0,
    name: str | None = None,
    origin: str = "real",
) -> StereoProfile:
    """A stereo profile from OpenCV stereo calibration file(s).

    Args:
        paths: one file with M1 D1 M2 D2 R T, or the sample's intrinsics.yml and extrinsics.yml.
        image_size: ``(width, height)`` in pixels when the files do not hold it.
        t_scale_m: metres per unit of the file's T (the square size when calibrated in squares).
    """
    files = [Path(paths)] if isinstance(paths, (str, Path)) else [Path(p) for p in paths]
    node_sets = [_read_nodes(p) for p in files]
    flavour = flavour_of(node_sets[0])
    if flavour is not None:  # ORB-SLAM, VINS-Fusion, Kimera-VIO settings: their own field names
        return load_settings(files, node_sets, flavour, read_filestorage_nodes, name=name, origin=origin,
                             image_size=image_size)
    data = read_opencv_stereo(files)
    first = data.paths[0]
    size = data.image_size or image_size
    R, T_file = data.R, data.T
    if (R is None or T_file is None) and data.rectified is not None:
        R, T_file = data.rectified
        log.info("%s: R and T recovered from R1 P1 R2 P2 (P's Tx taken in metres)", first)
    _require_all(first, size=size is not None, extrinsics=R is not None and T_file is not None,
                 R_missing=data.R is None)
    assert size is not None and R is not None and T_file is not None
    if not (t_scale_m > 0 and np.isfinite(t_scale_m)):
        raise FormatError(f"T scale must be a positive number of metres, got {t_scale_m}", field="--units-m")
    T = T_file * t_scale_m
    _check_t_units(T, t_scale_m, data.paths[-1])
    return build_stereo(
        name=name or first.stem, left=_camera(data, 1, size), right=_camera(data, 2, size), R=R, T=T,
        path=data.paths[-1], provenance=provenance_for(
            data.paths, "OpenCV FileStorage", origin=origin,
            notes="" if t_scale_m == 1.0 else f"T multiplied by {t_scale_m:g} (metres per unit of the file's T)"),
        description=f"imported from OpenCV FileStorage {', '.join(p.name for p in data.paths)}",
    )


def _require_all(first: Path, *, size: bool, extrinsics: bool, R_missing: bool) -> None:
    """One FormatError naming everything the file lacks (image size, extrinsics) and every fix at once."""
    missing, fixes, fields = [], [], []
    if not size:
        missing.append("the image size")
        fixes.append("pass --image-size WIDTHxHEIGHT (or state it in the file: size: [W, H], or image_width and "
                     "image_height)")
        fields.append("image_width/image_height")
    if not extrinsics:
        missing.append("the extrinsics R and T (it holds intrinsics only: M1 D1 M2 D2)")
        fixes.append("pass the extrinsics.yml written with it as a second file")
        fields.append("R" if R_missing else "T")
    if missing:
        raise FormatError(f"not in the file: {' and '.join(missing)}", path=first, field=", ".join(fields),
                          hint="; ".join(fixes))


def _check_t_units(T: FloatArray, t_scale_m: float, path: Path) -> None:
    """Refuse a baseline beyond :data:`MAX_BASELINE_M` naming the fix: ``--units-m`` (metres per unit of T)."""
    baseline = float(np.linalg.norm(T))
    if baseline <= MAX_BASELINE_M:
        return
    scaled = "" if t_scale_m == 1.0 else f" (after --units-m {t_scale_m:g})"
    raise FormatError(f"|T| = {baseline:g} m{scaled} is beyond the {MAX_BASELINE_M:g} m any stereo baseline has: T is "
                      "not in metres", path=path, field="T",
                      hint=f"pass --units-m 0.001 if T is in millimetres ({baseline * 0.001:.4g} m), or --units-m "
                      "SQUARE_M (the board's square size in metres) if it is in chessboard squares")


def opencv_to_text(profile: StereoProfile, *, xml: bool = False, rectification: bool = True) -> str:
    """The profile as OpenCV stereo FileStorage text (image size, M1 D1 M2 D2 R T, and R1 R2 P1 P2 Q)."""
    storage = cv2.FileStorage("out.xml" if xml else "out.yml", cv2.FILE_STORAGE_WRITE | cv2.FILE_STORAGE_MEMORY)
    storage.write("image_width", int(profile.image_size[0]))
    storage.write("image_height", int(profile.image_size[1]))
    if profile.left.distortion.model == "equidistant":
        storage.write("distortion_model", "equidistant")
    nodes = {"M1": profile.left.K, "D1": profile.left.D.reshape(1, -1), "M2": profile.right.K,
             "D2": profile.right.D.reshape(1, -1), "R": profile.R, "T": profile.T.reshape(3, 1)}
    if rectification:
        rect = stereo_rectification(profile)
        nodes.update(R1=rect.R1, R2=rect.R2, P1=rect.P1, P2=rect.P2, Q=rect.Q)
    for key, value in nodes.items():
        storage.write(key, np.ascontiguousarray(value, dtype=np.float64))
    return str(storage.releaseAndGetString())


def mono_opencv_text(profile: MonoProfile, *, xml: bool = False) -> str:
    """A mono profile as OpenCV's calibration sample writes one camera: image size, ``camera_matrix`` and
    ``distortion_coefficients`` (plus ``distortion_model`` for equidistant)."""
    storage = cv2.FileStorage("out.xml" if xml else "out.yml", cv2.FILE_STORAGE_WRITE | cv2.FILE_STORAGE_MEMORY)
    cam = profile.camera
    storage.write("image_width", int(cam.width_px))
    storage.write("image_height", int(cam.height_px))
    if cam.distortion.model == "equidistant":
        storage.write("distortion_model", "equidistant")
    storage.write("camera_matrix", np.ascontiguousarray(cam.K, dtype=np.float64))
    storage.write("distortion_coefficients", np.ascontiguousarray(cam.D.reshape(1, -1), dtype=np.float64))
    return str(storage.releaseAndGetString())


def dump_opencv(profile: StereoProfile, path: str | Path, *, force: bool = False, rectification: bool = True) -> Path:
    """Write the profile as OpenCV FileStorage (XML when ``path`` ends in .xml, else YAML), atomically."""
    out = Path(path)
    if profile.left.distortion.model != profile.right.distortion.model:
        raise FormatError("left and right distortion models differ; OpenCV files hold one model", path=out,
                          field="distortion")
    text = opencv_to_text(profile, xml=out.suffix.lower() == ".xml", rectification=rectification)
    return atomic_write_text(out, text, force=force)
