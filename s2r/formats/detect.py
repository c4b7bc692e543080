"""Content-based format detection and one loader for every supported stereo calibration format.

Detected from the file's content, never its name: s2r profile YAML, ROS camera_info (camera_calibration_parsers
YAML or ``rostopic echo`` text; two files or a folder holding left.yaml and right.yaml), OpenCV FileStorage
YAML/XML (one file, or intrinsics + extrinsics), Kalibr camchain YAML and RealSense ``rs-enumerate-devices -c``
text. Every failure is an :class:`~s2r.errors.S2RError` naming the file and field.
"""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Literal

from s2r.errors import FormatError
from s2r.formats._common import first_document, read_text, read_yaml
from s2r.formats.kalibr import is_kalibr_mapping, load_kalibr, strip_yaml_directive
from s2r.formats.realsense.facts import is_realsense_recording
from s2r.formats.realsense.recording import load_realsense_recording
from s2r.formats.realsense.text import is_realsense_text, load_realsense
from s2r.formats.ros_read import camera_info_from_filestorage, is_camera_info_mapping, load_ros_pair
from s2r.formats.s2r_yaml import load_profile_file
from s2r.formats.zed import is_zed_conf, load_zed
from s2r.geometry import baseline_layout_problem
from s2r.profile import StereoProfile

__all__ = ["FORMAT_NAMES", "Format", "check_layout", "detect_format", "is_robot_description", "load_any",
           "swap_cameras",
           "warn_implausible_baseline"]

log = logging.getLogger(__name__)

Format = Literal["s2r", "ros", "opencv", "kalibr", "realsense", "realsense_recording", "zed"]
#: Human names of the formats, as used in messages and provenance.
FORMAT_NAMES: dict[str, str] = {
    "s2r": "s2r profile YAML", "ros": "ROS camera_info", "opencv": "OpenCV FileStorage",
    "kalibr": "Kalibr camchain", "realsense": "rs-enumerate-devices text",
    "realsense_recording": "RealSense recording (.db3 / ROS 1 .bag)", "zed": "ZED SN*.conf",
}
_EXPECTED = (
    "expected an s2r profile, ROS camera_info, OpenCV FileStorage (stereo_calib, ORB-SLAM, VINS-Fusion, Kimera-VIO), "
    "Kalibr camchain, ZED SN*.conf, rs-enumerate-devices -c text or a RealSense recording (.db3 / .bag)"
)
#: Baselines outside this range (metres) are reported as implausible.
PLAUSIBLE_BASELINE_M = (0.002, 1.0)


def _is_opencv(text: str) -> bool:
    head = text.lstrip()[:200]
    return head.startswith("%YAML") or "opencv-matrix" in text or "<opencv_storage>" in head


_INI_SECTION = re.compile(r"^\s*\[([^\]\n]+)\]\s*$", re.MULTILINE)
_INI_ASSIGNMENT = re.compile(r"^\s*[A-Za-z_][\w.\- ]*=", re.MULTILINE)


def _is_ini(text: str) -> bool:
    """An INI file: its first line that is not blank or a comment is a ``[section]``, and it has ``key = value``
    lines (YAML writes ``key: value``)."""
    first = next((line for line in text.splitlines() if line.strip() and not line.lstrip().startswith(("#", ";"))),
                 "")
    return bool(_INI_SECTION.fullmatch(first)) and bool(_INI_ASSIGNMENT.search(text))


def _home_made_ini(text: str, path: Path) -> FormatError:
    """The refusal of an INI file that is not a ZED SN*.conf, named as what it is (with its sections)."""
    sections = ", ".join(f"[{s.strip()}]" for s in _INI_SECTION.findall(text)[:5])
    return FormatError(f"an INI file (sections {sections}) that is not a ZED SN*.conf ([LEFT_CAM_HD], "
                       "[RIGHT_CAM_HD], [STEREO] ...): s2r reads no home-made INI calibration", path=path,
                       hint="write the numbers as an s2r profile YAML or an OpenCV FileStorage (M1 D1 M2 D2 R T, "
                       "size: [W, H])")


def _is_s2r(data: dict[Any, Any]) -> bool:
    return "schema_version" in data or ("left" in data and "right" in data and "extrinsics" in data)


def _yaml_mapping(text: str, path: Path) -> dict[Any, Any] | None:
    """The first YAML document as a mapping (None when it is another YAML value); malformed: FormatError."""
    data = read_yaml(first_document(text), path)
    return data if isinstance(data, dict) else None


def detect_format(path: str | Path) -> Format:
    """The format of one file from its content; FormatError when it matches none."""
    source = Path(path)
    if source.is_dir():
        if (source / "left.yaml").is_file() and (source / "right.yaml").is_file():
            return "ros"
        raise FormatError("is a folder without left.yaml and right.yaml", path=source,
                          hint="pass a calibration file, or a folder holding a ROS left.yaml/right.yaml pair")
    if is_realsense_recording(source):  # binary: SQLite (.db3) or ROS 1 bag, told by their first bytes
        return "realsense_recording"
    text = read_text(source)
    if is_zed_conf(text):
        return "zed"
    if _is_ini(text):
        raise _home_made_ini(text, source)
    if _is_opencv(text):
        if _is_kalibr_text(text, source):
            return "kalibr"
        return "ros" if _is_filestorage_camera_info(text, source) else "opencv"
    if _is_robot_description(source, text):
        mjcf = "<mujoco" in text.lstrip()[:400]
        raise FormatError(f"is a {'MuJoCo model (MJCF)' if mjcf else 'robot description (URDF / xacro / SDF)'}, "
                          "not a camera profile", path=source, hint="derive a profile first: s2r profile "
                          f"{'from-description' if mjcf else 'from-urdf'} {source} -o profile.yaml")
    if is_realsense_text(text):
        return "realsense"
    if "schema_version" in text:
        return "s2r"  # its own loader names a malformed line or a bad field
    data = _yaml_mapping(text, source)
    if data is None:
        raise FormatError(f"unrecognised content: not a YAML mapping ({_EXPECTED})", path=source)
    if _is_s2r(data):
        return "s2r"
    if is_kalibr_mapping(data):
        return "kalibr"
    if is_camera_info_mapping(data):
        return "ros"
    keys = ", ".join(sorted(str(k) for k in data)[:6])
    raise FormatError(f"unrecognised format (top-level keys: {keys}); {_EXPECTED}", path=source)


def _is_filestorage_camera_info(text: str, path: Path) -> bool:
    """A ROS camera_info written by OpenCV's FileStorage (``%YAML:1.0``, ``!!opencv-matrix`` camera_matrix):
    image_width, camera_matrix, distortion_coefficients, rectification_matrix, projection_matrix."""
    if "projection_matrix" not in text or "camera_matrix" not in text or text.lstrip().startswith("<"):
        return False
    try:
        return is_camera_info_mapping(camera_info_from_filestorage(path))
    except FormatError:
        return False


def _is_kalibr_text(text: str, path: Path) -> bool:
    """A Kalibr camchain behind a ``%YAML:1.0`` line (OpenVINS writes them so): plain YAML once it is removed."""
    if "opencv-matrix" in text or text.lstrip().startswith("<"):
        return False
    try:
        data = read_yaml(strip_yaml_directive(text), path)
    except FormatError:
        return False
    return is_kalibr_mapping(data)


def is_robot_description(path: str | Path) -> bool:
    """True when ``path`` is a readable URDF, xacro, SDF or MJCF file (a sim camera's source, not a profile)."""
    source = Path(path)
    if not source.is_file():
        return False
    try:
        return _is_robot_description(source, read_text(source))
    except FormatError:
        return False


def _is_robot_description(path: Path, text: str) -> bool:
    """True for URDF, xacro, SDF and MJCF files (by suffix, or by their root element)."""
    if path.name.endswith((".urdf", ".xacro", ".sdf", ".world", ".gazebo")):
        return True
    head = text.lstrip()[:400]
    return head.startswith("<") and any(tag in head for tag in ("<robot", "<sdf", "<xacro:", "<mujoco"))


def _renamed(profile: StereoProfile, name: str | None) -> StereoProfile:
    if not name or name == profile.name:
        return profile
    data = profile.model_dump()
    data["name"] = name
    try:
        return StereoProfile.model_validate(data)
    except ValueError:
        raise FormatError(f"invalid profile name {name!r}", field="--name",
                          hint="use letters, digits, '_', '.' and '-'") from None


def _load_pair(paths: list[Path], fmts: list[Format], *, name: str | None, origin: str,
               image_size: tuple[int, int] | None, t_scale_m: float) -> StereoProfile:
    if fmts == ["ros", "ros"]:
        return load_ros_pair(paths[0], paths[1], name=name, origin=origin)
    if fmts == ["opencv", "opencv"]:
        from s2r.formats.opencv import load_opencv  # local: OpenCV loads only when needed

        return load_opencv(paths, image_size=image_size, t_scale_m=t_scale_m, name=name, origin=origin)
    found = " + ".join(FORMAT_NAMES[f] for f in fmts)
    raise FormatError(f"two inputs ({found}) must be a ROS camera_info pair or OpenCV intrinsics + extrinsics",
                      path=paths[1], hint="pass one file for the other formats")


def load_any(
    paths: str | Path | Sequence[str | Path],
    *,
    name: str | None = None,
    origin: str = "real",
    image_size: tuple[int, int] | None = None,
    t_scale_m: float = 1.0,
    resolution: tuple[int, int] | None = None,
    cameras: tuple[str | None, str | None] = (None, None),
    layout_warning: bool = True,
) -> StereoProfile:
    """Load a stereo profile from any supported format, detected from content.

    Args:
        paths: one file (s2r, OpenCV, Kalibr, RealSense text or recording, or a folder with ROS
            left.yaml/right.yaml) or two
            (ROS left + right camera_info; OpenCV intrinsics + extrinsics).
        name: profile name for imported formats (default derived from the file).
        origin: provenance origin of imported profiles (``real``, ``sim`` or ``nominal``).
        image_size: ``(width, height)`` for OpenCV files that do not hold it.
        t_scale_m: metres per unit of an OpenCV file's T (its square size when calibrated in squares).
        resolution: ``(width, height)`` of the RealSense infrared streams (or the ZED section) to import.
        cameras: ``(left, right)`` camera names of a Kalibr camchain (``camN``); default cam0 and cam1.
        layout_warning: warn about a pair lint calls a baseline error (False when the caller checks it itself
            with :func:`check_layout`).

    A baseline that is implausible for the camera (under 2 mm, or over 1 m when near objects would leave the
    image) is reported as a warning: a T in board squares or millimetres often looks like metres.
    """
    files = [Path(paths)] if isinstance(paths, (str, Path)) else [Path(p) for p in paths]
    if len(files) not in (1, 2):
        raise FormatError(f"expected one or two input files, got {len(files)}")
    fmts = [detect_format(p) for p in files]
    if len(files) == 2:
        profile = _load_pair(files, fmts, name=name, origin=origin, image_size=image_size, t_scale_m=t_scale_m)
    else:
        profile = _load_single(files[0], fmts[0], name=name, origin=origin, image_size=image_size,
                               t_scale_m=t_scale_m, resolution=resolution, cameras=cameras)
    warn_implausible_baseline(profile, files[-1])
    problem = baseline_layout_problem(-profile.R.T @ profile.T)
    if problem is not None and layout_warning:  # lint's and from-urdf's rule; convert and --to ros refuse it
        log.warning("%s: ERROR [%s] %s (%s)", files[-1], *problem, _layout_fix(problem[0]))
    return profile


def _layout_fix(code: str) -> str:
    if code == "baseline-side":
        return "`s2r profile convert --swap` exchanges the two cameras"
    return "check the file's R and T: the cameras must sit side by side"


def check_layout(profile: StereoProfile, path: str | Path, *, allow_bad_baseline: bool = False) -> None:
    """Refuse a pair that lint calls a baseline error (:func:`s2r.geometry.baseline_layout_problem`: the "right"
    camera on the left, or the baseline along the optical axis), as ``from-urdf`` does; with
    ``allow_bad_baseline`` it is a warning."""
    problem = baseline_layout_problem(-profile.R.T @ profile.T)
    if problem is None:
        return
    if allow_bad_baseline:
        log.warning("%s: ERROR [%s] %s (written anyway: --allow-bad-baseline)", path, *problem)
        return
    raise FormatError(f"[{problem[0]}] {problem[1]}", path=path, field="extrinsics",
                      hint=f"{_layout_fix(problem[0])}; or pass --allow-bad-baseline to write it anyway (from-urdf "
                      "and s2r lint apply the same rule)")


def swap_cameras(profile: StereoProfile) -> StereoProfile:
    """The profile with its cameras exchanged: the right camera becomes the left one, ``R' = R^T``,
    ``T' = -R^T T`` (OpenCV convention, metres); per-camera calibration figures follow their camera."""
    data = profile.model_dump()
    data["left"], data["right"] = data["right"], data["left"]
    data["extrinsics"]["rotation"] = profile.R.T.tolist()
    data["extrinsics"]["translation_m"] = (-profile.R.T @ profile.T).tolist()
    calibration = data["provenance"].get("calibration")
    if calibration:
        for a, b in (("rms_left_px", "rms_right_px"), ("coverage_left", "coverage_right")):
            calibration[a], calibration[b] = calibration[b], calibration[a]
    notes = data["provenance"]["notes"]
    data["provenance"]["notes"] = f"{notes}; left and right exchanged (--swap)" if notes else \
        "left and right exchanged (--swap)"
    return StereoProfile.model_validate(data)


def warn_implausible_baseline(profile: StereoProfile, path: Path) -> None:
    """Log a warning when the baseline does not fit the camera: under 2 mm, or over 1 m with the nearest depth
    seen by both cameras (disparity half the image width: ``fx B / (W / 2)``) beyond 3 m."""
    b = profile.baseline_m
    near = profile.left.fx_px * b / (profile.left.width_px / 2.0)
    if PLAUSIBLE_BASELINE_M[0] <= b <= PLAUSIBLE_BASELINE_M[1] or (b > PLAUSIBLE_BASELINE_M[1] and near <= 3.0):
        return
    log.warning("%s: baseline %.4g m is implausible for a %dx%d camera with %.1f deg HFOV (objects nearer than "
                "%.3g m would shift by more than half the image); if T is in board squares or millimetres, pass "
                "--units-m (metres per unit of T)", path, b, profile.left.width_px, profile.left.height_px,
                math.degrees(profile.left.hfov_rad), near)


def _load_single(source: Path, fmt: Format, *, name: str | None, origin: str, image_size: tuple[int, int] | None,
                 t_scale_m: float, resolution: tuple[int, int] | None,
                 cameras: tuple[str | None, str | None]) -> StereoProfile:
    if fmt == "s2r":
        return _renamed(load_profile_file(source), name)
    if fmt == "ros":
        if source.is_dir():
            return load_ros_pair(source / "left.yaml", source / "right.yaml", name=name or source.name, origin=origin)
        raise FormatError("a camera_info file holds one camera; a stereo profile needs two", path=source,
                          hint="pass the left and the right camera_info files together")
    if fmt == "opencv":
        from s2r.formats.opencv import load_opencv  # local: OpenCV loads only when needed

        return load_opencv(source, image_size=image_size, t_scale_m=t_scale_m, name=name, origin=origin)
    if fmt == "kalibr":
        return load_kalibr(source, name=name, origin=origin, left=cameras[0], right=cameras[1])
    if fmt == "zed":
        return load_zed(source, resolution=resolution, name=name, origin=origin)
    if fmt == "realsense_recording":
        return load_realsense_recording(source, name=name, origin=origin)
    return load_realsense(source, resolution=resolution, name=name, origin=origin)
