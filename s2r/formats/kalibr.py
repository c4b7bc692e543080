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

from s2r.errors import FormatError
from s2r.fileio import atomic_write_text
from s2r.formats._common import (
    as_int,
    as_matrix,
    build_camera,
    build_stereo,
    check_rotation_field,
    distortion_for,
    provenance_for,
    read_text,
    read_yaml,
    require,
)
from s2r.profile import Camera, StereoProfile

__all__ = ["dump_kalibr", "is_kalibr_mapping", "kalibr_to_yaml", "load_kalibr"]

log = logging.getLogger(__name__)

_KNOWN_KEYS = {"camera_model", "intrinsics", "distortion_model", "distortion_coeffs", "resolution", "rostopic",
               "cam_overlaps", "T_cn_cnm1", "T_cam_imu", "timeshift_cam_imu", "line_delay"}


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
    if dist_model == "radtan":
        if len(coeffs) != 4:
            raise FormatError(f"radtan needs 4 coefficients (k1 k2 r1 r2), got {len(coeffs)}", path=path, field=field)
        distortion = distortion_for("plumb_bob", [*coeffs.tolist(), 0.0], path, field)
    elif dist_model == "equidistant":
        distortion = distortion_for("equidistant", coeffs.tolist(), path, field)
    elif dist_model == "none":
        distortion = distortion_for("plumb_bob", [], path, field)
    else:
        raise FormatError(f"distortion model {dist_model!r} is not supported (radtan, equidistant, none)",
                          path=path, field=f"{key}.distortion_model")
    K = np.array([[fu, 0.0, pu], [0.0, fv, pv], [0.0, 0.0, 1.0]])
    return build_camera(K=K, size=(width, height), distortion=distortion, path=path, field=f"{key}.intrinsics")


def load_kalibr(
    path: str | Path, *, name: str | None = None, origin: str = "real", left: str = "cam0", right: str = "cam1"
) -> StereoProfile:
    """A stereo profile from a Kalibr camchain: ``left``/``right`` cameras, ``right.T_cn_cnm1`` as ``[R | T]``."""
    source = Path(path)
    data = read_yaml(read_text(source), source)
    if not isinstance(data, dict):
        raise FormatError("expected a mapping with cam0 and cam1", path=source, hint="is this a Kalibr camchain?")
    lcam, rcam = _camera(data, left, source), _camera(data, right, source)
    field = f"{right}.T_cn_cnm1"
    transform = as_matrix(require(data[right], "T_cn_cnm1", source, prefix=f"{right}."), (4, 4), source, field)
    if np.max(np.abs(transform[3] - np.array([0.0, 0.0, 0.0, 1.0]))) > 1e-9:
        raise FormatError("last row must be [0, 0, 0, 1]", path=source, field=field)
    R = check_rotation_field(transform[:3, :3], source, field)
    return build_stereo(
        name=name or source.stem, left=lcam, right=rcam, R=R, T=transform[:3, 3].copy(), path=source,
        provenance=provenance_for([source], "Kalibr camchain", origin=origin),
        description=f"imported from Kalibr camchain {source.name}",
    )


def _camera_entry(cam: Camera, *, drop_k3: bool, label: str, path: Path | None) -> dict[str, Any]:
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
    cam0 = {**_camera_entry(profile.left, drop_k3=drop_k3, label="left", path=path), "cam_overlaps": [1],
            "rostopic": "/cam0/image_raw"}
    transform = np.eye(4)
    transform[:3, :3], transform[:3, 3] = profile.R, profile.T
    cam1 = {"T_cn_cnm1": transform.tolist(), **_camera_entry(profile.right, drop_k3=drop_k3, label="right", path=path),
            "cam_overlaps": [0], "rostopic": "/cam1/image_raw"}
    header = f"# Kalibr camchain exported by s2r from profile {profile.name}\n"
    return header + yaml.safe_dump({"cam0": cam0, "cam1": cam1}, sort_keys=False, default_flow_style=None,
                                   width=1000)


def dump_kalibr(profile: StereoProfile, path: str | Path, *, force: bool = False, drop_k3: bool = False) -> Path:
    """Write the profile as a Kalibr camchain YAML atomically; refuses k3 != 0 unless ``drop_k3``."""
    return atomic_write_text(path, kalibr_to_yaml(profile, drop_k3=drop_k3, path=Path(path)), force=force)
