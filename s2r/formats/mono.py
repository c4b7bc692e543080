"""A mono profile (``s2r calibrate --mono``) in the outside formats: one ROS camera_info, one Kalibr camera,
OpenCV's calibration-sample layout (``camera_matrix``, ``distortion_coefficients``, ``image_width/height``).

The camera_info of a mono camera is unrectified: ``R = I`` and ``P = [K | 0]`` (as camera_calibration writes it).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import yaml

from s2r.errors import S2RError
from s2r.fileio import atomic_write_text, read_text_file
from s2r.profile import MonoProfile
from s2r.safeparse import parse_yaml

__all__ = ["dump_mono", "is_mono_profile_file", "mono_to_kalibr_yaml", "mono_to_ros_yaml"]


def is_mono_profile_file(path: str | Path) -> bool:
    """True for an s2r profile YAML that holds one camera (``camera:``, no ``left:``)."""
    source = Path(path)
    if not source.is_file():
        return False
    try:
        data = parse_yaml(read_text_file(source), path=source)
    except (S2RError, OSError):
        return False  # the reader that handles the file reports what is wrong with it
    return isinstance(data, dict) and "schema_version" in data and "camera" in data and "left" not in data


def mono_to_ros_yaml(profile: MonoProfile) -> str:
    """camera_calibration_parsers YAML of the camera: its K and D, ``R = I``, ``P = [K | 0]``."""
    from s2r.formats.ros import RosCameraInfo, camera_info_to_yaml  # local: profile show needs no ROS module

    cam = profile.camera
    P = np.hstack([cam.K, np.zeros((3, 1))])
    info = RosCameraInfo(camera_name=profile.name, width=cam.width_px, height=cam.height_px, K=cam.K, D=cam.D,
                         distortion_model=cam.distortion.model, R=np.eye(3), P=P, frame_id=cam.frame_id)
    return camera_info_to_yaml(info)


def mono_to_kalibr_yaml(profile: MonoProfile, *, drop_k3: bool = False) -> str:
    """A one-camera Kalibr camchain (``cam0``)."""
    from s2r.formats.kalibr import camera_entry

    cam0: dict[str, Any] = {**camera_entry(profile.camera, drop_k3=drop_k3, label="camera", path=None),
                            "rostopic": "/cam0/image_raw"}
    header = f"# Kalibr camchain (one camera) exported by s2r from profile {profile.name}\n"
    return header + yaml.safe_dump({"cam0": cam0}, sort_keys=False, default_flow_style=None, width=1000)


def dump_mono(profile: MonoProfile, path: str | Path, fmt: str, *, force: bool = False, drop_k3: bool = False) -> Path:
    """Write ``profile`` as ``fmt`` (``ros``: one camera_info file, ``kalibr``, ``opencv``) atomically."""
    if fmt == "ros":
        return atomic_write_text(path, mono_to_ros_yaml(profile), force=force)
    if fmt == "kalibr":
        return atomic_write_text(path, mono_to_kalibr_yaml(profile, drop_k3=drop_k3), force=force)
    from s2r.formats.opencv import mono_opencv_text  # local: OpenCV loads only when needed

    return atomic_write_text(path, mono_opencv_text(profile, xml=Path(path).suffix.lower() == ".xml"), force=force)
