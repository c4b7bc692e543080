"""Reading ROS camera_info: one file (:func:`read_camera_info`, the camera_calibration_parsers YAML, ``rostopic
echo`` text of ROS 1 or 2, or OpenCV FileStorage) and a rectified pair of them into a profile (:func:`load_ros_pair`),
inverting the export of :mod:`s2r.formats.ros` (whose docstring derives R and T) and reading back its ``s2r:`` block.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import ValidationError

from s2r.errors import FormatError
from s2r.formats._common import (
    as_float,
    as_int,
    as_matrix,
    build_camera,
    build_stereo,
    distortion_for,
    first_document,
    provenance_for,
    read_text,
    read_yaml,
    require,
    rotation_as_printed,
)
from s2r.formats.filestorage import read_filestorage
from s2r.formats.ros import ZERO_DISTORTION_MARKER, RosCameraInfo
from s2r.formats.s2r_yaml import validation_message
from s2r.profile import Camera, MatcherSettings, StereoProfile

__all__ = ["camera_info_from_filestorage", "is_camera_info_mapping", "load_ros_pair", "read_camera_info"]

log = logging.getLogger(__name__)
FloatArray = NDArray[np.float64]
#: Pixel conventions the ``s2r:`` block may name (s2r.profile.Convention).
_CONVENTIONS = ("gazebo-classic", "gz-sim", "exact", "opencv")


#: Keys of the two text layouts: camera_calibration_parsers YAML, and rostopic echo (ROS 1 upper, ROS 2 lower).
_YAML_KEYS = {"width": "image_width", "height": "image_height", "K": "camera_matrix", "D": "distortion_coefficients",
              "model": "distortion_model", "R": "rectification_matrix", "P": "projection_matrix"}
_ECHO_KEYS = {"width": "width", "height": "height", "K": "K", "D": "D", "model": "distortion_model", "R": "R",
              "P": "P"}


def _is_parsers_layout(keys: set[str]) -> bool:
    return bool(keys & {"camera_matrix", "projection_matrix", "rectification_matrix", "distortion_coefficients"})


def is_camera_info_mapping(data: Any) -> bool:
    """True when ``data`` looks like a camera_info (either the parsers' YAML or rostopic echo)."""
    if not isinstance(data, dict):
        return False
    keys = {str(k) for k in data}
    return _is_parsers_layout(keys) or len(keys & {"K", "D", "R", "P", "k", "d", "r", "p"}) >= 2


def _plain(value: Any) -> Any:
    """FileStorage values as the parsers' YAML has them: arrays -> flat lists, whole floats in sizes -> int."""
    if isinstance(value, np.ndarray):
        return [float(v) for v in value.reshape(-1)]
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


def camera_info_from_filestorage(path: Path) -> dict[Any, Any]:
    """A camera_info written by OpenCV's FileStorage (``%YAML:1.0``, ``!!opencv-matrix``) as a plain mapping."""
    data = {k: _plain(v) for k, v in read_filestorage(path).items()}
    for key in ("image_width", "image_height"):
        if isinstance(data.get(key), float) and float(data[key]).is_integer():
            data[key] = int(data[key])
    return data


def _parse_mapping(text: str, path: Path) -> dict[Any, Any]:
    if text.lstrip().startswith("%YAML") or "opencv-matrix" in text:
        return camera_info_from_filestorage(path)
    data = read_yaml(first_document(text), path)
    if not isinstance(data, dict):
        raise FormatError("expected a camera_info mapping (image_width, camera_matrix, ... or K:, P:)", path=path,
                          hint="pass a camera_calibration_parsers YAML or saved `rostopic echo` output")
    return data


def _matrix_field(data: dict[Any, Any], key: str, shape: tuple[int, int], path: Path) -> FloatArray:
    value = require(data, key, path)
    if isinstance(value, dict):  # the parsers' layout {rows, cols, data}
        rows = as_int(require(value, "rows", path, prefix=f"{key}."), path, f"{key}.rows")
        cols = as_int(require(value, "cols", path, prefix=f"{key}."), path, f"{key}.cols")
        if (rows, cols) != shape:
            raise FormatError(f"expected rows {shape[0]} cols {shape[1]}, got {rows} x {cols}", path=path, field=key)
        value = require(value, "data", path, prefix=f"{key}.")
    return as_matrix(value, shape, path, key)


def _coefficients(data: dict[Any, Any], key: str, path: Path) -> list[float]:
    value = require(data, key, path)
    if isinstance(value, dict):
        value = require(value, "data", path, prefix=f"{key}.")
    if value is None:
        return []
    if not isinstance(value, (list, tuple)):
        raise FormatError(f"expected a list of numbers, got {type(value).__name__}", path=path, field=key)
    return [as_float(v, path, key) for v in value]


def _lower_keys(data: dict[Any, Any]) -> dict[Any, Any]:
    """ROS 2 echo prints k, d, r, p: map them to the ROS 1 names."""
    upper = {"k": "K", "d": "D", "r": "R", "p": "P"}
    return {upper.get(k, k) if isinstance(k, str) else k: v for k, v in data.items()}


def read_camera_info(path: str | Path) -> RosCameraInfo:
    """Read one camera_info: a camera_calibration_parsers YAML file or saved ``rostopic echo`` text.

    Raises:
        FormatError: naming the file and the field (missing, not a number, wrong count, zero focal
            length, principal point outside the image, R not a rotation, NaN/inf, unknown model).
    """
    source = Path(path)
    data = _parse_mapping(read_text(source), source)
    keys = _YAML_KEYS if _is_parsers_layout({str(k) for k in data}) else _ECHO_KEYS
    if keys is _ECHO_KEYS:
        data = _lower_keys(data)
    width = as_int(require(data, keys["width"], source), source, keys["width"])
    height = as_int(require(data, keys["height"], source), source, keys["height"])
    K = _matrix_field(data, keys["K"], (3, 3), source)
    model = require(data, keys["model"], source)
    if not isinstance(model, str):
        raise FormatError(f"expected a model name, got {type(model).__name__}", path=source, field=keys["model"])
    coeffs = _coefficients(data, keys["D"], source)
    extra = _s2r_block(data, source)
    if extra.get("zero_distortion") is True and coeffs and coeffs[-1] == ZERO_DISTORTION_MARKER:
        coeffs[-1] = 0.0  # the marker s2r wrote so image_proc rectifies: the camera has no distortion
    distortion = distortion_for(model, coeffs, source, keys["D"])
    rectified = keys["R"] in data or keys["P"] in data  # neither: one camera's intrinsics (lint needs no more)
    if rectified:
        R = rotation_as_printed(_matrix_field(data, keys["R"], (3, 3), source), source, keys["R"],
                                zero_is_identity=True)
        P = _matrix_field(data, keys["P"], (3, 4), source)
    else:
        R, P = np.eye(3), np.c_[K, np.zeros(3)]
    build_camera(K=K, size=(width, height), distortion=distortion, path=source, field=keys["K"])
    header = data.get("header")
    frame_id = header.get("frame_id", "") if isinstance(header, dict) else extra.get("frame_id", "")
    name = data.get("camera_name", "")
    return RosCameraInfo(
        camera_name=name if isinstance(name, str) else str(name), width=width, height=height, K=K,
        D=np.array(distortion.coefficients, dtype=np.float64), distortion_model=model, R=R, P=P,
        frame_id=frame_id if isinstance(frame_id, str) else str(frame_id), s2r=extra, rectified=rectified,
    )


def _s2r_block(data: dict[Any, Any], path: Path) -> dict[str, Any]:
    """The ``s2r:`` mapping s2r's export adds (absent in other files): checked, unknown keys ignored."""
    block = data.get("s2r")
    if block is None:
        return {}
    if not isinstance(block, dict):
        raise FormatError(f"expected a mapping, got {type(block).__name__}", path=path, field="s2r")
    out: dict[str, Any] = {}
    convention = block.get("convention")
    if convention is not None:
        if convention not in _CONVENTIONS:
            raise FormatError(f"unknown pixel convention {convention!r} (one of {', '.join(_CONVENTIONS)})",
                              path=path, field="s2r.convention")
        out["convention"] = convention
    if block.get("matcher") is not None:
        try:
            out["matcher"] = MatcherSettings.model_validate(block["matcher"])
        except ValidationError as exc:
            loc, msg = validation_message(exc)
            raise FormatError(msg, path=path, field=f"s2r.matcher.{loc}") from None
    for key, kind in (("frame_id", str), ("zero_distortion", bool)):
        if block.get(key) is not None:
            if not isinstance(block[key], kind):
                raise FormatError(f"expected a {kind.__name__}", path=path, field=f"s2r.{key}")
            out[key] = block[key]
    return out


def _rectified_offset(info: RosCameraInfo, path: Path, field: str) -> FloatArray:
    """``t`` in ``P = K' [I | t]`` (metres, rectified frame)."""
    k_rect = info.P[:, :3]
    if abs(float(np.linalg.det(k_rect))) < 1e-12 or k_rect[0, 0] <= 0:
        raise FormatError("left 3x3 block of P is singular; cannot recover the extrinsics", path=path, field=field,
                          hint="export camera_info from a calibrated stereo pair")
    return np.asarray(np.linalg.solve(k_rect, info.P[:, 3]), dtype=np.float64)


def _camera(info: RosCameraInfo, path: Path) -> Camera:
    distortion = distortion_for(info.distortion_model, info.D.tolist(), path, "distortion_coefficients")
    return build_camera(K=info.K, size=info.image_size, distortion=distortion, path=path, field="camera_matrix",
                        frame_id=info.frame_id)


def load_ros_pair(
    left_path: str | Path, right_path: str | Path, *, name: str | None = None, origin: str = "real"
) -> StereoProfile:
    """A stereo profile from two camera_info files (parsers YAML or rostopic echo text, in any mix).

    ``R = R2^T R1`` and ``T = R2^T (t2 - t1)`` with ``t = K'^-1 P[:, 3]`` (see the module docstring).
    """
    lpath, rpath = Path(left_path), Path(right_path)
    left, right = read_camera_info(lpath), read_camera_info(rpath)
    for info, path in ((left, lpath), (right, rpath)):
        if not info.rectified:
            raise FormatError("holds one camera's intrinsics but no stereo extrinsics (no rectification_matrix, no "
                              "projection_matrix)", path=path, field="rectification_matrix",
                              hint="a stereo profile needs the pair's rectified camera_info (R and P, as "
                              "camera_calibration writes them) or a stereo calibration file (OpenCV R T, Kalibr)")
    if left.image_size != right.image_size:
        raise FormatError(
            f"image size {right.width}x{right.height} differs from {left.width}x{left.height} in {lpath}",
            path=rpath, field="image_width/image_height", hint="pass the two camera_info files of one stereo pair",
        )
    t_left = _rectified_offset(left, lpath, "projection_matrix")
    t_right = _rectified_offset(right, rpath, "projection_matrix")
    R = right.R.T @ left.R
    T = right.R.T @ (t_right - t_left)
    if float(np.linalg.norm(T)) < 1e-6:
        raise FormatError("P[0,3] (Tx) is 0 in both files: no baseline between the cameras", path=rpath,
                          field="projection_matrix", hint="the right camera's Tx must be -fx' * baseline; "
                          "pass the left file first and the right file second")
    if T[0] > 0 and abs(T[0]) >= abs(T[1]):
        log.warning("%s: the second camera sits to the LEFT of the first (T_x = %+.4f m); pass the left camera's "
                    "file first", rpath, T[0])
    base = name or (left.camera_name.split("/")[0] if left.camera_name else lpath.parent.name or lpath.stem)
    profile = build_stereo(
        name=base, left=_camera(left, lpath), right=_camera(right, rpath), R=R, T=T, path=rpath,
        provenance=provenance_for([lpath, rpath], "ROS camera_info", origin=origin),
        description=f"imported from ROS camera_info {lpath.name} + {rpath.name}",
    )
    return _with_s2r_block(profile, left.s2r, rpath)


def _with_s2r_block(profile: StereoProfile, block: dict[str, Any], path: Path) -> StereoProfile:
    """The profile with the pixel convention and matcher settings s2r's export kept in the ``s2r:`` block."""
    if not block.get("convention") and "matcher" not in block:
        return profile
    data = profile.model_dump()
    if block.get("convention"):
        data["provenance"]["convention"] = block["convention"]
    if "matcher" in block:
        data["matcher"] = block["matcher"].model_dump()
    try:
        return StereoProfile.model_validate(data)
    except ValidationError as exc:
        loc, msg = validation_message(exc)
        raise FormatError(msg, path=path, field=f"s2r: {loc}") from None
