"""Kalibr camchain YAML (``cam0`` / ``cam1``): pinhole cameras with radtan or equidistant distortion.

Per camera: ``camera_model: pinhole``, ``intrinsics: [fu, fv, pu, pv]`` (pixels),
``distortion_model: radtan`` with ``distortion_coeffs: [k1, k2, r1, r2]`` (OpenCV's k1 k2 p1 p2; radtan
has NO k3) or ``equidistant`` with ``[k1, k2, k3, k4]``, and ``resolution: [width, height]``.
``cam1.T_cn_cnm1`` is the 4x4 transform taking points from cam0's frame into cam1's, i.e.
``[R | T]`` in OpenCV's convention (``X_right = R X_left + T``, metres).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from s2r.errors import FormatError
from s2r.fileio import atomic_write_text
from s2r.formats._common import (
    as_int,
    as_matrix,
    build_camera,
    build_stereo,
    distortion_for,
    provenance_for,
    read_text,
    read_yaml,
    require,
    rotation_as_printed,
)
from s2r.geometry import baseline_layout_problem, invert_transform
from s2r.profile import Camera, StereoProfile

__all__ = ["camera_entry", "dump_kalibr", "is_kalibr_mapping", "kalibr_to_yaml", "load_kalibr", "strip_yaml_directive"]

log = logging.getLogger(__name__)
FloatArray = NDArray[np.float64]

_KNOWN_KEYS = {"camera_model", "intrinsics", "distortion_model", "distortion_coeffs", "resolution", "rostopic",
               "cam_overlaps", "T_cn_cnm1", "T_cam_imu", "T_imu_cam", "timeshift_cam_imu", "line_delay"}


def is_kalibr_mapping(data: Any) -> bool:
    """True when ``data`` looks like a Kalibr camchain (a ``cam0`` mapping with intrinsics)."""
    cam0 = data.get("cam0") if isinstance(data, dict) else None
    return isinstance(cam0, dict) and bool({"camera_model", "intrinsics", "distortion_model"} & set(cam0))


def _camera(data: dict[Any, Any], key: str, path: Path) -> Camera:
    cam = require(data, key, path)
    prefix = f"{key}."
    if not isinstance(cam, dict):
        raise FormatError("expected a mapping", path=path, field=key)
    unknown = sorted(str(k) for k in cam if k not in _KNOWN_KEYS)
    if unknown:
        log.warning("%s: %s: ignoring unknown Kalibr fields %s", path, key, ", ".join(unknown))
    model = require(cam, "camera_model", path, prefix=prefix)
    if model != "pinhole":
        raise FormatError(f"camera model {model!r} is not supported", path=path, field=f"{key}.camera_model",
                          hint="s2r reads pinhole cameras (radtan or equidistant distortion)")
    fu, fv, pu, pv = as_matrix(require(cam, "intrinsics", path, prefix=prefix), (4,), path, f"{key}.intrinsics")
    size = as_matrix(require(cam, "resolution", path, prefix=prefix), (2,), path, f"{key}.resolution")
    width, height = as_int(size[0], path, f"{key}.resolution"), as_int(size[1], path, f"{key}.resolution")
    dist_model = require(cam, "distortion_model", path, prefix=prefix)
    field = f"{key}.distortion_coeffs"
    raw = require(cam, "distortion_coeffs", path, prefix=prefix)
    if not isinstance(raw, list):
        raise FormatError("expected a list of numbers", path=path, field=field)
    coeffs = as_matrix(raw, (len(raw),), path, field)
    if dist_model in ("radtan", "plumb_bob"):  # plumb_bob: hand-written chains with ROS's name, k3 allowed
        if len(coeffs) != 4 and not (dist_model == "plumb_bob" and len(coeffs) == 5):
            allowed = "4 coefficients (k1 k2 r1 r2)" + (" or 5 (+ k3)" if dist_model == "plumb_bob" else "")
            raise FormatError(f"{dist_model} needs {allowed}, got {len(coeffs)}", path=path, field=field)
        distortion = distortion_for("plumb_bob", [*coeffs.tolist(), 0.0][:5], path, field)
    elif dist_model == "equidistant":
        distortion = distortion_for("equidistant", coeffs.tolist(), path, field)
    elif dist_model == "none":
        distortion = distortion_for("plumb_bob", [], path, field)
    else:
        raise FormatError(f"distortion model {dist_model!r} is not supported (radtan, plumb_bob, equidistant, none)",
                          path=path, field=f"{key}.distortion_model")
    K = np.array([[fu, 0.0, pu], [0.0, fv, pv], [0.0, 0.0, 1.0]])
    return build_camera(K=K, size=(width, height), distortion=distortion, path=path, field=f"{key}.intrinsics")


def strip_yaml_directive(text: str) -> str:
    """``text`` without the ``%YAML:1.0`` line that OpenCV-minded tools (every OpenVINS config) prepend, which
    a YAML 1.1 parser refuses, and without a ``---`` document start right after it."""
    lines = text.splitlines()
    while lines and (lines[0].lstrip().startswith("%YAML") or not lines[0].strip()):
        lines.pop(0)
    if lines and lines[0].strip() == "---":
        lines.pop(0)
    return "\n".join(lines)


def _transform(data: dict[Any, Any], key: str, field: str, path: Path) -> FloatArray:
    transform = as_matrix(require(data[key], field, path, prefix=f"{key}."), (4, 4), path, f"{key}.{field}")
    if np.max(np.abs(transform[3] - np.array([0.0, 0.0, 0.0, 1.0]))) > 1e-9:
        raise FormatError("last row must be [0, 0, 0, 1]", path=path, field=f"{key}.{field}")
    transform[:3, :3] = rotation_as_printed(transform[:3, :3], path, f"{key}.{field}")
    return transform


def _cam_from_imu(data: dict[Any, Any], key: str, path: Path) -> FloatArray | None:
    """``T_cam_imu`` of ``key`` (Kalibr's camchain-imucam), or the inverse of OpenVINS' ``T_imu_cam``."""
    if "T_cam_imu" in data[key]:
        return _transform(data, key, "T_cam_imu", path)
    if "T_imu_cam" in data[key]:
        return invert_transform(_transform(data, key, "T_imu_cam", path))
    return None


def _index(key: str) -> int | None:
    return int(key[3:]) if key.startswith("cam") and key[3:].isdigit() else None


def _right_from_left(data: dict[Any, Any], left: str, right: str, path: Path) -> tuple[FloatArray, str]:
    """``T_right_left`` (OpenCV ``[R | T]``) and how it was obtained: the ``T_cn_cnm1`` chain from ``left`` up to
    ``right``, else ``T_right_imu @ inv(T_left_imu)``."""
    i, j = _index(left), _index(right)
    if i is not None and j is not None and i != j:
        lo, hi = min(i, j), max(i, j)
        entries = [data.get(f"cam{n}") for n in range(lo + 1, hi + 1)]
        if all(isinstance(e, dict) and "T_cn_cnm1" in e for e in entries):
            T = np.eye(4)
            for n in range(lo + 1, hi + 1):
                T = _transform(data, f"cam{n}", "T_cn_cnm1", path) @ T
            how = "T_cn_cnm1" if hi == lo + 1 else f"the T_cn_cnm1 chain cam{lo + 1}..cam{hi}"
            return (T, how) if j > i else (invert_transform(T), f"the inverse of {how}")
    left_imu, right_imu = _cam_from_imu(data, left, path), _cam_from_imu(data, right, path)
    if left_imu is not None and right_imu is not None:
        return right_imu @ invert_transform(left_imu), "T_cam_imu of both cameras (T_c1_c0 = T_c1_imu inv(T_c0_imu))"
    raise FormatError(f"no extrinsics between {left} and {right}: {right} has no T_cn_cnm1 and the cameras do not "
                      "both have T_cam_imu / T_imu_cam", path=path, field=f"{right}.T_cn_cnm1",
                      hint="pass a camchain with T_cn_cnm1, or a camchain-imucam with T_cam_imu for both cameras")


def _choose(data: dict[Any, Any], left: str | None, right: str | None, path: Path) -> tuple[str, str]:
    cams = sorted((k for k in data if isinstance(k, str) and _index(k) is not None), key=lambda k: _index(k) or 0)
    if left is None and right is None and len(cams) < 2:
        raise FormatError(f"a camchain with {len(cams)} camera(s) ({', '.join(cams) or 'none'}): a stereo profile "
                          "needs two", path=path, field="cam1", hint="pass the stereo camchain (cam0 and cam1)")
    if left is None and right is None:
        left, right = "cam0", "cam1"
        if len(cams) > 2:
            log.warning("%s: %d cameras (%s); using cam0 as left and cam1 as right (choose with --left camN "
                        "--right camM)", path, len(cams), ", ".join(cams))
    for option, key in (("--left", left), ("--right", right)):
        if key not in data:
            raise FormatError(f"no camera {key!r} (cameras: {', '.join(cams) or 'none'})", path=path, field=option,
                              hint="pass --left camN --right camM with two of the listed cameras")
    assert left is not None and right is not None
    if left == right:
        raise FormatError("--left and --right name the same camera", path=path, field="--right")
    return left, right


def load_kalibr(
    path: str | Path, *, name: str | None = None, origin: str = "real", left: str | None = None,
    right: str | None = None,
) -> StereoProfile:
    """A stereo profile from a Kalibr camchain (``%YAML:1.0`` first line accepted, as OpenVINS writes it).

    ``left``/``right`` name the cameras (default cam0 and cam1; a chain with more cameras says which were used).
    Extrinsics: ``right.T_cn_cnm1`` (or the chain of them) as ``[R | T]``, else from ``T_cam_imu`` (Kalibr
    camchain-imucam) or ``T_imu_cam`` (OpenVINS): ``T_c1_c0 = T_c1_imu inv(T_c0_imu)``.
    """
    source = Path(path)
    data = read_yaml(strip_yaml_directive(read_text(source)), source)
    if not isinstance(data, dict):
        raise FormatError("expected a mapping with cam0 and cam1", path=source, hint="is this a Kalibr camchain?")
    lkey, rkey = _choose(data, left, right, source)
    lcam, rcam = _camera(data, lkey, source), _camera(data, rkey, source)
    transform, how = _right_from_left(data, lkey, rkey, source)
    position = invert_transform(transform)[:3, 3]  # the right camera's origin in the left optical frame
    problem = baseline_layout_problem(position)
    if left is None and right is None and problem is not None and problem[0] == "baseline-side":
        # camN numbers are not sides (OpenVINS' Hilti and D435i chains list the right imager first)
        log.warning("%s: %s is %.1f cm to the LEFT of %s: using %s as left and %s as right (choose with --left "
                    "--right)", source, rkey, -position[0] * 100, lkey, rkey, lkey)
        lkey, rkey, lcam, rcam = rkey, lkey, rcam, lcam
        transform, how = _right_from_left(data, lkey, rkey, source)
    log.info("%s: left %s, right %s; extrinsics from %s", source, lkey, rkey, how)
    return build_stereo(
        name=name or source.stem, left=lcam, right=rcam, R=transform[:3, :3].copy(), T=transform[:3, 3].copy(),
        path=source, provenance=provenance_for([source], "Kalibr camchain", origin=origin,
                                               notes=f"left {lkey}, right {rkey}; extrinsics from {how}"),
        description=f"imported from Kalibr camchain {source.name} ({lkey} + {rkey})",
    )


def camera_entry(cam: Camera, *, drop_k3: bool, label: str, path: Path | None) -> dict[str, Any]:
    """One camera's Kalibr entry (pinhole, radtan or equidistant); refuses k3 != 0 unless ``drop_k3``."""
    coeffs = [float(c) for c in cam.distortion.coefficients]
    if cam.distortion.model == "plumb_bob":
        if coeffs[4] != 0.0 and not drop_k3:
            raise FormatError(f"k3 = {coeffs[4]:g} cannot be written: Kalibr radtan has only k1 k2 r1 r2",
                              path=path, field=f"{label}.distortion",
                              hint="pass --drop-k3 to write it without k3 (lossy)")
        if coeffs[4] != 0.0:
            log.warning("%s: dropping k3 = %g (Kalibr radtan has no k3); the export is lossy", label, coeffs[4])
        model, coeffs = "radtan", coeffs[:4]
    elif cam.distortion.model == "equidistant":
        model = "equidistant"
    else:
        raise FormatError(f"distortion model {cam.distortion.model} has no Kalibr equivalent",
                          path=path, field=f"{label}.distortion",
                          hint="Kalibr supports radtan (plumb_bob) and equidistant")
    if cam.skew != 0.0:
        log.warning("%s: skew %g dropped (Kalibr pinhole has no skew)", label, cam.skew)
    return {"camera_model": "pinhole", "intrinsics": [cam.fx_px, cam.fy_px, cam.cx_px, cam.cy_px],
            "distortion_model": model, "distortion_coeffs": coeffs, "resolution": [cam.width_px, cam.height_px]}


def kalibr_to_yaml(profile: StereoProfile, *, drop_k3: bool = False, path: Path | None = None) -> str:
    """The profile as Kalibr camchain YAML text (full float precision); ``path`` only names errors."""
    cam0 = {**camera_entry(profile.left, drop_k3=drop_k3, label="left", path=path), "cam_overlaps": [1],
            "rostopic": "/cam0/image_raw"}
    transform = np.eye(4)
    transform[:3, :3], transform[:3, 3] = profile.R, profile.T
    cam1 = {"T_cn_cnm1": transform.tolist(), **camera_entry(profile.right, drop_k3=drop_k3, label="right", path=path),
            "cam_overlaps": [0], "rostopic": "/cam1/image_raw"}
    header = f"# Kalibr camchain exported by s2r from profile {profile.name}\n"
    return header + yaml.safe_dump({"cam0": cam0, "cam1": cam1}, sort_keys=False, default_flow_style=None,
                                   width=1000)


def dump_kalibr(profile: StereoProfile, path: str | Path, *, force: bool = False, drop_k3: bool = False) -> Path:
    """Write the profile as a Kalibr camchain YAML atomically; refuses k3 != 0 unless ``drop_k3``."""
    return atomic_write_text(path, kalibr_to_yaml(profile, drop_k3=drop_k3, path=Path(path)), force=force)
