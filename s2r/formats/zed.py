"""Stereolabs ZED factory calibration ``SN<serial>.conf`` (INI): per-resolution intrinsics and the stereo pose.

Sections ``[LEFT_CAM_<RES>]`` / ``[RIGHT_CAM_<RES>]`` hold ``fx fy cx cy`` (pixels) and ``k1 k2 p1 p2 k3``
(OpenCV plumb_bob) for RES in 2K (2208x1242), FHD (1920x1080), HD (1280x720) and VGA (672x376).
``[STEREO]`` holds ``Baseline`` (MILLIMETRES), ``TY``/``TZ`` (mm, optionally suffixed ``_<RES>``) and the
rotation vector ``(RX, CV, RZ)_<RES>`` (radians; CV is the convergence about y). As Stereolabs'
zed-opencv-native sample feeds them to ``cv2.stereoRectify``: ``R = Rodrigues(RX, CV, RZ)`` and
``T = (-Baseline, TY, TZ)``, OpenCV's ``X_right = R X_left + T``; s2r converts T to metres.
"""

from __future__ import annotations

import configparser
from pathlib import Path

import numpy as np

from s2r.errors import FormatError
from s2r.formats._common import as_float, build_camera, build_stereo, distortion_for, provenance_for, read_text
from s2r.profile import Camera, StereoProfile

__all__ = ["ZED_RESOLUTIONS", "is_zed_conf", "load_zed"]

#: Resolution names of the conf file and their image sizes (width, height) per eye.
ZED_RESOLUTIONS: dict[str, tuple[int, int]] = {"2K": (2208, 1242), "FHD": (1920, 1080), "HD": (1280, 720),
                                               "VGA": (672, 376)}


def is_zed_conf(text: str) -> bool:
    """True for a ZED ``SN*.conf`` (an INI file with ``[LEFT_CAM_<RES>]`` sections, RES one of
    :data:`ZED_RESOLUTIONS`, and ``[STEREO]``); another INI file is not one, however it names its sections."""
    return "[STEREO]" in text and any(f"[LEFT_CAM_{res}]" in text for res in ZED_RESOLUTIONS)


def _parse(path: Path) -> configparser.ConfigParser:
    parser = configparser.ConfigParser(interpolation=None)
    try:
        parser.read_string(read_text(path))
    except configparser.Error as exc:
        raise FormatError(f"malformed ZED conf (INI): {' '.join(str(exc).split())}", path=path) from None
    return parser


def _number(section: configparser.SectionProxy, key: str, path: Path, default: float | None = None) -> float:
    field = f"[{section.name}] {key}"
    if key not in section:
        if default is not None:
            return default
        raise FormatError("field is missing", path=path, field=field)
    try:
        value = float(section[key])
    except ValueError:
        raise FormatError(f"expected a number, got {section[key]!r}", path=path, field=field) from None
    return as_float(value, path, field)


def _camera(parser: configparser.ConfigParser, side: str, res: str, path: Path) -> Camera:
    name = f"{side}_CAM_{res}"
    if name not in parser:
        raise FormatError("section is missing", path=path, field=f"[{name}]")
    sec = parser[name]
    K = np.array([[_number(sec, "fx", path), 0.0, _number(sec, "cx", path)],
                  [0.0, _number(sec, "fy", path), _number(sec, "cy", path)], [0.0, 0.0, 1.0]])
    coeffs = [_number(sec, k, path, 0.0) for k in ("k1", "k2", "p1", "p2", "k3")]
    distortion = distortion_for("plumb_bob", coeffs, path, f"[{name}]")
    return build_camera(K=K, size=ZED_RESOLUTIONS[res], distortion=distortion, path=path, field=f"[{name}]")


def _resolution(parser: configparser.ConfigParser, wanted: tuple[int, int] | None, path: Path) -> str:
    available = [r for r in ZED_RESOLUTIONS if f"LEFT_CAM_{r}" in parser and f"RIGHT_CAM_{r}" in parser]
    listed = ", ".join(f"{r} {ZED_RESOLUTIONS[r][0]}x{ZED_RESOLUTIONS[r][1]}" for r in available) or "none"
    if wanted is None:
        if "HD" in available:
            return "HD"
        if len(available) == 1:
            return available[0]
        raise FormatError(f"pick a resolution (available: {listed})", path=path, field="--resolution")
    found = [r for r in available if ZED_RESOLUTIONS[r] == wanted]
    if not found:
        raise FormatError(f"resolution {wanted[0]}x{wanted[1]} not in the file (available: {listed})", path=path,
                          field="--resolution")
    return found[0]


def load_zed(path: str | Path, *, resolution: tuple[int, int] | None = None, name: str | None = None,
             origin: str = "real") -> StereoProfile:
    """A stereo profile from a ZED ``SN*.conf`` at ``resolution`` (per-eye ``(width, height)``; default HD 1280x720)."""
    source = Path(path)
    parser = _parse(source)
    res = _resolution(parser, resolution, source)
    if "STEREO" not in parser:
        raise FormatError("section is missing", path=source, field="[STEREO]")
    stereo = parser["STEREO"]
    baseline_mm = _number(stereo, "Baseline", source)
    ty = _number(stereo, f"TY_{res}", source, _number(stereo, "TY", source, 0.0))
    tz = _number(stereo, f"TZ_{res}", source, _number(stereo, "TZ", source, 0.0))
    rvec = [_number(stereo, f"{k}_{res}", source, 0.0) for k in ("RX", "CV", "RZ")]
    from scipy.spatial.transform import Rotation  # local: profile show/convert start without scipy

    R = np.asarray(Rotation.from_rotvec(rvec).as_matrix(), dtype=np.float64)  # = cv2.Rodrigues(rvec)
    T = np.array([-baseline_mm, ty, tz]) / 1000.0
    return build_stereo(
        name=name or f"zed_{source.stem}_{res}", left=_camera(parser, "LEFT", res, source),
        right=_camera(parser, "RIGHT", res, source), R=R, T=T, path=source,
        provenance=provenance_for([source], "ZED conf", origin=origin,
                                  notes=f"{res} section; Baseline/TY/TZ in mm converted to metres"),
        description=f"ZED factory calibration {source.name} at {res}",
    )
