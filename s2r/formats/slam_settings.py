"""Stereo settings of SLAM systems, read from their OpenCV FileStorage nodes (no OpenCV needed here).

- ORB-SLAM3 (``File.version: "1.0"``): ``Camera1.fx/fy/cx/cy/k1/k2/p1/p2[/k3]``, ``Camera2.*``,
  ``Camera.width/height`` and ``Stereo.T_c1_c2``: the pose of camera 2 in camera 1 (it maps points from c2 to
  c1), so OpenCV's ``[R | T] = inv(T_c1_c2)``. ``Camera.type: KannalaBrandt8`` uses ``k1..k4`` (equidistant);
  ``Camera.type: Rectified`` has only ``Camera1.*`` and ``Stereo.b`` (metres): R = I, ``T = (-b, 0, 0)``.
- ORB-SLAM2 / old ORB-SLAM3 (``Camera.fx`` ... ``Camera.bf``): with ``LEFT.K/D/R/P`` and ``RIGHT.K/D/R/P`` the raw
  pair is recovered as from ROS camera_info (``R = R2^T R1``, ``T = R2^T (t2 - t1)``, ``t = K'^-1 P[:, 3]``);
  without them the images are already rectified: K from ``Camera.fx/fy/cx/cy``, no distortion, R = I and
  ``T = (-bf / fx, 0, 0)`` metres. Early ORB-SLAM3 files with ``Camera.*``, ``Camera2.*`` and ``Tlr`` (right camera
  in the left frame) are a raw pair: ``[R | T] = inv(Tlr)``.
- VINS-Fusion: ``body_T_cam0`` / ``body_T_cam1`` (camera poses in the body/IMU frame) and ``cam0_calib`` /
  ``cam1_calib`` camera files (camodocal ``PINHOLE``: ``projection_parameters`` fx fy cx cy,
  ``distortion_parameters`` k1 k2 p1 p2) beside the config; ``[R | T] = inv(body_T_cam1) body_T_cam0``.
- Kimera-VIO: one file per camera (``camera_id``, ``T_BS`` = camera pose in the body frame, ``intrinsics``
  [fu, fv, cu, cv], ``distortion_model`` radial-tangential / equidistant, ``distortion_coefficients``,
  ``resolution``); a pair gives ``[R | T] = inv(T_BS_right) T_BS_left``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.errors import FormatError
from s2r.formats._common import (
    as_float,
    as_int,
    as_matrix,
    build_camera,
    build_stereo,
    distortion_for,
    provenance_for,
    rotation_as_printed,
)
from s2r.geometry import invert_transform
from s2r.profile import Camera, Distortion, StereoProfile

__all__ = ["SETTINGS_FLAVOURS", "flavour_of", "load_settings"]

log = logging.getLogger(__name__)
FloatArray = NDArray[np.float64]
Nodes = Mapping[str, Any]
ReadNodes = Callable[[Path], dict[str, Any]]
#: Flavour -> human name (messages, provenance).
SETTINGS_FLAVOURS = {"orbslam3": "ORB-SLAM3 settings", "orbslam2": "ORB-SLAM2 settings", "vins": "VINS-Fusion config",
                     "vins_camera": "VINS-Fusion camera file", "kimera": "Kimera-VIO camera params"}


def flavour_of(nodes: Nodes) -> str | None:
    """Which SLAM settings file ``nodes`` come from (a key of :data:`SETTINGS_FLAVOURS`), None for others."""
    if "Camera1.fx" in nodes:
        return "orbslam3"
    if "Camera.fx" in nodes or "LEFT.K" in nodes:
        return "orbslam2"
    if "body_T_cam0" in nodes or "cam0_calib" in nodes:
        return "vins"
    if "projection_parameters" in nodes and "model_type" in nodes:
        return "vins_camera"
    if "T_BS" in nodes and "intrinsics" in nodes:
        return "kimera"
    return None


def _num(nodes: Nodes, key: str, path: Path) -> float:
    if key not in nodes:
        raise FormatError("required field is missing (add it)", path=path, field=key)
    value = nodes[key]
    if isinstance(value, np.ndarray) and value.size == 1:
        value = float(value.reshape(-1)[0])
    return as_float(value, path, key)


def _matrix(nodes: Nodes, key: str, shape: tuple[int, int], path: Path) -> FloatArray:
    if key not in nodes:
        raise FormatError("required field is missing (add it)", path=path, field=key)
    value = nodes[key]
    if isinstance(value, dict):  # a plain {rows, cols, data} map (Kimera) rather than an !!opencv-matrix
        value = value.get("data")
    if isinstance(value, np.ndarray):
        value = value.tolist()
    return as_matrix(value, shape, path, key)


def _pose(nodes: Nodes, key: str, path: Path) -> FloatArray:
    T = _matrix(nodes, key, (4, 4), path)
    if np.max(np.abs(T[3] - np.array([0.0, 0.0, 0.0, 1.0]))) > 1e-9:
        raise FormatError("last row must be [0, 0, 0, 1]", path=path, field=key)
    T[:3, :3] = rotation_as_printed(T[:3, :3], path, key)
    return T


def _size(nodes: Nodes, wkey: str, hkey: str, path: Path,
          fallback: tuple[int, int] | None = None) -> tuple[int, int]:
    """Image size from ``wkey``/``hkey``; ``fallback`` (``--image-size``) when the file has neither."""
    if fallback is not None and wkey not in nodes and hkey not in nodes:
        return fallback
    if wkey not in nodes:
        raise FormatError("required field is missing (add it, or pass --image-size WIDTHxHEIGHT)", path=path,
                          field=wkey)
    return as_int(_num(nodes, wkey, path), path, wkey), as_int(_num(nodes, hkey, path), path, hkey)


def _K(fx: float, fy: float, cx: float, cy: float) -> FloatArray:
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def _orbslam3_camera(nodes: Nodes, p: str, size: tuple[int, int], path: Path) -> Camera:
    """One camera of ORB-SLAM3 settings, its fields prefixed ``p`` (``Camera1.``, ``Camera2.``; ``Camera.``)."""
    K = _K(*(_num(nodes, p + k, path) for k in ("fx", "fy", "cx", "cy")))
    kind = str(nodes.get("Camera.type", "PinHole")).strip().strip('"')
    if kind == "KannalaBrandt8":
        distortion = distortion_for("equidistant", [_num(nodes, p + k, path) for k in ("k1", "k2", "k3", "k4")],
                                    path, p + "k1")
    elif kind == "PinHole":
        coeffs = [_num(nodes, p + k, path) if p + k in nodes else 0.0 for k in ("k1", "k2", "p1", "p2", "k3")]
        distortion = distortion_for("plumb_bob", coeffs, path, p + "k1")
    else:
        raise FormatError(f"camera type {kind!r} is not supported (PinHole, KannalaBrandt8)", path=path,
                          field="Camera.type")
    return build_camera(K=K, size=size, distortion=distortion, path=path, field=p + "fx")


def _orbslam3(nodes: Nodes, path: Path, hint: tuple[int, int] | None) -> tuple[Camera, Camera, FloatArray, str]:
    kind = str(nodes.get("Camera.type", "PinHole")).strip().strip('"')
    if kind == "Rectified" and "Stereo.b" in nodes:  # already rectified images: one K, no distortion, baseline b
        size = _size(nodes, "Camera.width", "Camera.height", path, hint)
        K = _K(*(_num(nodes, "Camera1." + k, path) for k in ("fx", "fy", "cx", "cy")))
        camera = build_camera(K=K, size=size, distortion=Distortion(), path=path, field="Camera1.fx")
        T = np.eye(4)
        T[0, 3] = -_num(nodes, "Stereo.b", path)
        return camera, camera, T, "Stereo.b (metres) of the rectified pair"
    if "Camera2.fx" not in nodes or "Stereo.T_c1_c2" not in nodes:
        raise FormatError("an ORB-SLAM3 settings file without Camera2 and Stereo.T_c1_c2 holds one camera (monocular "
                          "or rectified stereo: Stereo.b)", path=path, field="Camera2.fx",
                          hint="a stereo profile needs both cameras and Stereo.T_c1_c2")
    size = _size(nodes, "Camera.width", "Camera.height", path, hint)
    T_c2_c1 = invert_transform(_pose(nodes, "Stereo.T_c1_c2", path))  # T_c1_c2 maps c2 points into c1
    return (_orbslam3_camera(nodes, "Camera1.", size, path), _orbslam3_camera(nodes, "Camera2.", size, path), T_c2_c1,
            "Stereo.T_c1_c2 (pose of camera 2 in camera 1, inverted)")


def _rectified_offset(K_rect: FloatArray, P: FloatArray, path: Path, field: str) -> FloatArray:
    if abs(float(np.linalg.det(K_rect))) < 1e-12:
        raise FormatError("left 3x3 block of P is singular", path=path, field=field)
    return np.asarray(np.linalg.solve(K_rect, P[:, 3]), dtype=np.float64)


def _orbslam2_side(nodes: Nodes, side: str, path: Path) -> tuple[Camera, FloatArray, FloatArray]:
    size = _size(nodes, f"{side}.width", f"{side}.height", path)
    raw = nodes.get(f"{side}.D")
    coeffs = [] if raw is None else [float(v) for v in np.asarray(raw, dtype=np.float64).reshape(-1)]
    distortion = distortion_for("plumb_bob", (coeffs + [0.0] * 5)[:5] if len(coeffs) <= 5 else coeffs, path,
                                f"{side}.D")
    camera = build_camera(K=_matrix(nodes, f"{side}.K", (3, 3), path), size=size, distortion=distortion, path=path,
                          field=f"{side}.K")
    R = rotation_as_printed(_matrix(nodes, f"{side}.R", (3, 3), path), path, f"{side}.R")
    return camera, R, _matrix(nodes, f"{side}.P", (3, 4), path)


def _orbslam3_old(nodes: Nodes, path: Path, hint: tuple[int, int] | None) -> tuple[Camera, Camera, FloatArray, str]:
    """Early ORB-SLAM3 layout (TUM_512.yaml): ``Camera.*`` and ``Camera2.*`` and ``Tlr``, the 3x4 pose of the
    right camera in the left one (it maps right points into the left frame): ``[R | T] = inv(Tlr)``."""
    size = _size(nodes, "Camera.width", "Camera.height", path, hint)
    T_l_r = np.eye(4)
    T_l_r[:3, :] = _matrix(nodes, "Tlr", (3, 4), path)
    T_l_r[:3, :3] = rotation_as_printed(T_l_r[:3, :3], path, "Tlr")
    return (_orbslam3_camera(nodes, "Camera.", size, path), _orbslam3_camera(nodes, "Camera2.", size, path),
            invert_transform(T_l_r), "Tlr (pose of the right camera in the left one, inverted)")


@dataclass(frozen=True)
class _Block:
    """One reading of ORB-SLAM2 settings: the pair, how its extrinsics were found, and what ORB-SLAM's tracker
    sees of it (rectified image size in pixels, fx' in pixels, bf = fx' * baseline in pixel metres)."""

    left: Camera
    right: Camera
    T: FloatArray
    how: str
    size: tuple[int, int]
    fx: float
    bf: float

    def describe(self) -> str:
        """``752x480, fx 435.205, bf 47.906 (B 110.1 mm)``."""
        return (f"{self.size[0]}x{self.size[1]}, fx {self.fx:.6g}, bf {self.bf:.6g} "
                f"(B {1000 * self.bf / self.fx:.1f} mm)")


def _is_placeholder(value: Any) -> bool:
    """An empty node: ``LEFT.height:`` with no value, or an opencv-matrix with ``data: []``."""
    return value is None or (isinstance(value, np.ndarray) and value.size == 0) or \
        (isinstance(value, str) and not value.strip())


def _leftright_state(nodes: Nodes) -> str:
    """``absent`` (no LEFT./RIGHT. node), ``empty`` (every one a placeholder) or ``filled``."""
    values = [v for k, v in nodes.items() if k.startswith(("LEFT.", "RIGHT."))]
    if not values:
        return "absent"
    return "empty" if all(_is_placeholder(v) for v in values) else "filled"


def _leftright(nodes: Nodes, path: Path) -> _Block:
    """The raw pair from ``LEFT/RIGHT.K D R P`` (as ROS camera_info: ``R = R2^T R1``, ``T = R2^T (t2 - t1)``)."""
    left, R1, P1 = _orbslam2_side(nodes, "LEFT", path)
    right, R2, P2 = _orbslam2_side(nodes, "RIGHT", path)
    t1 = _rectified_offset(P1[:, :3], P1, path, "LEFT.P")
    t2 = _rectified_offset(P2[:, :3], P2, path, "RIGHT.P")
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R2.T @ R1, R2.T @ (t2 - t1)
    return _Block(left, right, T, "LEFT/RIGHT R and P (as ROS camera_info)", left.image_size, float(P1[0, 0]),
                  float(P1[0, 3] - P2[0, 3]))


def _camera_bf(nodes: Nodes, path: Path, hint: tuple[int, int] | None) -> _Block:
    """One camera ``Camera.fx/fy/cx/cy[/k1 k2 p1 p2 k3]`` for both images (row-aligned once undistorted, as
    ORB-SLAM2's tracker assumes), ``R = I`` and ``T = (-bf / fx, 0, 0)`` metres."""
    fx = _num(nodes, "Camera.fx", path)
    K = _K(fx, _num(nodes, "Camera.fy", path), _num(nodes, "Camera.cx", path), _num(nodes, "Camera.cy", path))
    size = _size(nodes, "Camera.width", "Camera.height", path, hint)
    coeffs = [_num(nodes, "Camera." + k, path) if "Camera." + k in nodes else 0.0 for k in ("k1", "k2", "p1", "p2",
                                                                                              "k3")]
    distortion = distortion_for("plumb_bob", coeffs, path, "Camera.k1")
    camera = build_camera(K=K, size=size, distortion=distortion, path=path, field="Camera.fx")
    bf = _num(nodes, "Camera.bf", path)
    T = np.eye(4)
    T[0, 3] = -bf / fx
    return _Block(camera, camera, T, "Camera.bf / Camera.fx (row-aligned images)", size, fx, bf)


def _agree(a: _Block, b: _Block) -> bool:
    """Same image size, fx and bf within 0.1 % (the comment in ORB-SLAM's EuRoC file: "Camera.fx, .fy, etc must
    be the same as in LEFT.P")."""
    return a.size == b.size and abs(a.fx - b.fx) <= 1e-3 * b.fx and abs(a.bf - b.bf) <= 1e-3 * abs(b.bf)


def _check_without_bf(nodes: Nodes, path: Path, hint: tuple[int, int] | None, pair: _Block) -> None:
    """Refuse LEFT/RIGHT blocks whose size or fx' disagree with a ``Camera.*`` block that has no ``Camera.bf``:
    neither reading is then complete and consistent."""
    if "Camera.fx" not in nodes:
        return
    fx, size = _num(nodes, "Camera.fx", path), _size(nodes, "Camera.width", "Camera.height", path, hint)
    if size != pair.size or abs(fx - pair.fx) > 1e-3 * pair.fx:
        raise FormatError(f"the LEFT/RIGHT blocks ({pair.describe()}) disagree with Camera.* ({size[0]}x{size[1]}, "
                          f"fx {fx:.6g}), which has no Camera.bf to stand on its own", path=path, field="Camera.bf",
                          hint="fix or delete the LEFT/RIGHT blocks (leftovers of another camera?) and give "
                          "Camera.bf = fx * baseline")


def _attempt(read: Callable[[], _Block]) -> tuple[_Block | None, FormatError | None]:
    try:
        return read(), None
    except FormatError as exc:
        return None, exc


def _orbslam2(nodes: Nodes, path: Path, hint: tuple[int, int] | None) -> tuple[Camera, Camera, FloatArray, str]:
    """ORB-SLAM2 settings: the ``LEFT/RIGHT`` raw pair when it agrees with ``Camera.*`` (or ``Camera.*`` is
    incomplete), else the ``Camera.*`` + ``Camera.bf`` block that ORB-SLAM's tracker uses, with a warning naming
    the disagreement (leftover EuRoC ``LEFT/RIGHT`` blocks are common). Empty placeholders are skipped."""
    if "Camera2.fx" in nodes and "Tlr" in nodes:
        return _orbslam3_old(nodes, path, hint)
    state = _leftright_state(nodes)
    pair, pair_error = _attempt(lambda: _leftright(nodes, path)) if state == "filled" else (None, None)
    block, block_error = _attempt(lambda: _camera_bf(nodes, path, hint)) if "Camera.bf" in nodes else (None, None)
    if pair is not None and "Camera.bf" not in nodes:
        _check_without_bf(nodes, path, hint, pair)
    if pair is not None and (block is None or _agree(pair, block)):
        if block_error is not None:
            log.warning("%s: Camera.* is incomplete (%s: %s); using the LEFT/RIGHT blocks (%s)", path,
                        block_error.field, block_error.message, pair.describe())
        return pair.left, pair.right, pair.T, pair.how
    if block is not None:
        if pair is not None:
            log.warning("%s: the LEFT/RIGHT blocks (%s) disagree with Camera.* (%s); using Camera.*, the camera "
                        "ORB-SLAM tracks with (LEFT/RIGHT only pre-rectify the images: fix or delete them)", path,
                        pair.describe(), block.describe())
        elif pair_error is not None:
            log.warning("%s: the LEFT/RIGHT blocks are unusable (%s: %s); using Camera.* (%s)", path,
                        pair_error.field, pair_error.message, block.describe())
        elif state == "empty":
            log.info("%s: the LEFT/RIGHT blocks are empty placeholders; using Camera.* (%s)", path, block.describe())
        return block.left, block.right, block.T, block.how
    error = pair_error or block_error
    if error is not None:
        raise error
    raise FormatError("holds one camera (no Camera.bf, no LEFT/RIGHT): a monocular ORB-SLAM settings file",
                      path=path, field="Camera.bf", hint="a stereo profile needs the stereo settings file")


def _camodocal(nodes: Nodes, path: Path) -> tuple[Camera, str]:
    model = str(nodes.get("model_type", "")).strip()
    if model != "PINHOLE":
        raise FormatError(f"camera model {model!r} is not supported (PINHOLE)", path=path, field="model_type")
    proj, dist = nodes.get("projection_parameters"), nodes.get("distortion_parameters")
    if not isinstance(proj, dict) or not isinstance(dist, dict):
        raise FormatError("expected projection_parameters and distortion_parameters maps", path=path,
                          field="projection_parameters")
    K = _K(*(_num(proj, k, path) for k in ("fx", "fy", "cx", "cy")))
    coeffs = [_num(dist, k, path) for k in ("k1", "k2", "p1", "p2")] + [0.0]
    size = _size(nodes, "image_width", "image_height", path)
    camera = build_camera(K=K, size=size, distortion=distortion_for("plumb_bob", coeffs, path, "distortion_parameters"),
                          path=path, field="projection_parameters")
    return camera, str(nodes.get("camera_name", ""))


def _vins(nodes: Nodes, path: Path, read_nodes: ReadNodes) -> tuple[Camera, Camera, FloatArray, str]:
    if as_int(_num(nodes, "num_of_cam", path), path, "num_of_cam") < 2:
        raise FormatError("num_of_cam is 1: a monocular VINS-Fusion config", path=path, field="num_of_cam",
                          hint="a stereo profile needs a config with num_of_cam: 2")
    cams = []
    for n in (0, 1):
        name = nodes.get(f"cam{n}_calib")
        if not isinstance(name, str) or not name:
            raise FormatError("required field is missing (the camera file's name)", path=path, field=f"cam{n}_calib")
        cam_path = path.parent / name
        if not cam_path.is_file():
            raise FormatError(f"camera file {cam_path} not found", path=path, field=f"cam{n}_calib",
                              hint="keep the camera files beside the config, as VINS-Fusion reads them")
        cams.append(_camodocal(read_nodes(cam_path), cam_path)[0])
    T = invert_transform(_pose(nodes, "body_T_cam1", path)) @ _pose(nodes, "body_T_cam0", path)
    return cams[0], cams[1], T, "body_T_cam0 and body_T_cam1 (T_c1_c0 = inv(body_T_cam1) body_T_cam0)"


def _kimera_camera(nodes: Nodes, path: Path) -> tuple[Camera, FloatArray]:
    if str(nodes.get("camera_model", "pinhole")).strip() != "pinhole":
        raise FormatError(f"camera model {nodes.get('camera_model')!r} is not supported (pinhole)", path=path,
                          field="camera_model")
    fu, fv, cu, cv = _matrix(nodes, "intrinsics", (1, 4), path).reshape(-1)
    res = _matrix(nodes, "resolution", (1, 2), path).reshape(-1)
    size = (as_int(res[0], path, "resolution"), as_int(res[1], path, "resolution"))
    raw = np.asarray(nodes.get("distortion_coefficients", []), dtype=np.float64).reshape(-1).tolist()
    model = str(nodes.get("distortion_model", "radial-tangential")).strip()
    if model in ("radial-tangential", "radtan"):
        distortion = distortion_for("plumb_bob", (raw + [0.0] * 5)[:5], path, "distortion_coefficients")
    elif model == "equidistant":
        distortion = distortion_for("equidistant", raw, path, "distortion_coefficients")
    else:
        raise FormatError(f"distortion model {model!r} is not supported (radial-tangential, equidistant)", path=path,
                          field="distortion_model")
    camera = build_camera(K=_K(fu, fv, cu, cv), size=size, distortion=distortion, path=path, field="intrinsics")
    return camera, _pose(nodes, "T_BS", path)


def load_settings(paths: list[Path], node_sets: list[dict[str, Any]], flavour: str, read_nodes: ReadNodes, *,
                  name: str | None, origin: str, image_size: tuple[int, int] | None = None) -> StereoProfile:
    """A stereo profile from SLAM settings (``flavour`` from :func:`flavour_of` on ``node_sets[0]``);
    ``image_size`` for ORB-SLAM files without ``Camera.width/height``."""
    first = paths[0]
    if flavour in ("vins_camera", "kimera") and len(paths) != 2:
        raise FormatError(f"a {SETTINGS_FLAVOURS[flavour]} holds one camera; a stereo profile needs two", path=first,
                          hint="pass the main VINS-Fusion config (it names both camera files)" if flavour ==
                          "vins_camera" else "pass LeftCameraParams.yaml and RightCameraParams.yaml together")
    if len(paths) == 2 and flavour != "kimera":
        raise FormatError(f"a {SETTINGS_FLAVOURS[flavour]} is one file", path=paths[1], hint="pass it alone")
    if flavour == "orbslam3":
        left, right, T, how = _orbslam3(node_sets[0], first, image_size)
    elif flavour == "orbslam2":
        left, right, T, how = _orbslam2(node_sets[0], first, image_size)
    elif flavour == "vins":
        left, right, T, how = _vins(node_sets[0], first, read_nodes)
    else:
        left, T_B_left = _kimera_camera(node_sets[0], paths[0])
        right, T_B_right = _kimera_camera(node_sets[1], paths[1])
        T, how = invert_transform(T_B_right) @ T_B_left, "T_BS of both cameras (inv(T_BS_right) T_BS_left)"
    return build_stereo(
        name=name or first.stem, left=left, right=right, R=T[:3, :3].copy(), T=T[:3, 3].copy(), path=paths[-1],
        provenance=provenance_for(paths, SETTINGS_FLAVOURS[flavour], origin=origin, notes=f"extrinsics from {how}"),
        description=f"imported from {SETTINGS_FLAVOURS[flavour]} {', '.join(p.name for p in paths)}",
    )
