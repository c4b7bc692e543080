"""The sim profile of a chosen stereo pair of a robot description: :func:`profile_from_pair`, with the seed
matcher settings the profile starts from (:func:`seed_matcher`).

Below the checks of the pair (:mod:`s2r.sources.lint`) and :mod:`s2r.sources.profile_builder`, which reads a
description, checks its pair and calls this; both import it.
"""

from __future__ import annotations

import hashlib
import logging
import math
import re
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from pydantic import ValidationError

from s2r.errors import SourceError
from s2r.fileio import MAX_TEXT_BYTES, read_regular_file, sha256_file
from s2r.geometry import opencv_extrinsics_from_pose
from s2r.profile import (
    Camera,
    Distortion,
    Extrinsics,
    MatcherSettings,
    Provenance,
    SimulationSettings,
    SourceFile,
    StereoProfile,
)
from s2r.sources.conventions import (
    CENTRE_OFFSET_PX,
    Intrinsics,
    classic_distortion_scale,
    crop_magnification,
    gazebo_to_opencv_distortion,
    gz_sim_distortion_scale,
    intrinsics_for,
    scale_distortion,
)
from s2r.sources.description import OPTICAL_SUFFIXES, CameraSpec, Description
from s2r.sources.loader import StereoPair, optical_pose
from s2r.sources.mjcf.reader import SENSOR_TYPE as MJCF_SENSOR_TYPE

__all__ = ["DEFAULT_CLIP_M", "SEED_SGBM", "profile_from_pair", "renders_as_link", "seed_matcher"]

logger = logging.getLogger(__name__)

#: The seed tutorial's StereoSGBM settings (REFERENCE.md): 112 disparities, block 5, P1 8*3*5^2, P2 32*3*5^2.
SEED_SGBM: dict[str, int] = {
    "min_disparity": 0, "num_disparities": 112, "block_size": 5, "p1": 8 * 3 * 25, "p2": 32 * 3 * 25,
    "disp12_max_diff": 1, "uniqueness_ratio": 10, "speckle_window_size": 100, "speckle_range": 32,
}
#: Gazebo's defaults for an absent ``<clip>``, metres.
DEFAULT_CLIP_M = (0.1, 100.0)


def seed_matcher(fx_px: float, baseline_m: float, width_px: int, *, far_limit_m: float) -> MatcherSettings:
    """The seed's SGBM with a working range it can see: min_depth_m is fx B / 111 px (the largest disparity
    of 112) rounded UP to the centimetre, max_depth_m where the theoretical RMS reaches 2 % (s = 0.08 px),
    capped at ``far_limit_m``. Falls back to defaults when 112 disparities do not fit the image."""
    fb = fx_px * baseline_m
    if SEED_SGBM["num_disparities"] >= width_px or fb <= 0:
        return MatcherSettings()
    d_max = SEED_SGBM["min_disparity"] + SEED_SGBM["num_disparities"] - 1
    min_depth = math.ceil(100.0 * fb / d_max) / 100.0
    max_depth = min(far_limit_m, math.floor(10.0 * 0.02 * fb / 0.08) / 10.0)
    max_depth = max(max_depth, 2.0 * min_depth)
    return MatcherSettings(algorithm="sgbm", min_depth_m=min_depth, max_depth_m=max_depth, **SEED_SGBM)


def _simulator(spec: CameraSpec, description: Description | None, convention: str) -> str | None:
    """The simulator whose advice applies to ``spec``: the one the file loads, else the convention's, else None."""
    guess = description.simulator if description is not None else None
    if guess is not None and guess.simulator is not None:
        return guess.simulator
    if spec.plugin is not None:
        return "gazebo-classic"  # a gazebo_ros camera plugin on the camera itself
    return convention if convention in ("gazebo-classic", "gz-sim") else None


def _distortion(spec: CameraSpec, k: Intrinsics, convention: str, simulator: str | None = None) -> Distortion:
    d = spec.distortion
    if d is None or d.is_zero:
        return Distortion()
    offset = CENTRE_OFFSET_PX[convention]
    coeffs: tuple[float, ...] = (d.k1, d.k2, d.k3, d.p1, d.p2)
    if convention == "gz-sim":  # gz-rendering's units: image-normalised ones scaled by 2 tan(fov / 2)
        coeffs = scale_distortion(coeffs, 1.0 / gz_sim_distortion_scale(spec.width, spec.height, spec.hfov_rad))
    elif not d.legacy_mode:  # Gazebo classic's <ignition:legacy_mode>false</ignition:legacy_mode> (PR 3009)
        coeffs = scale_distortion(coeffs, 1.0 / classic_distortion_scale(spec.width, spec.height, spec.hfov_rad))
    _warn_crop(spec, coeffs, d.center, simulator)
    fit = gazebo_to_opencv_distortion(*coeffs, width=spec.width, height=spec.height,
                                      fx=k.fx, fy=k.fy, center=d.center, principal=(k.cx - offset, k.cy - offset))
    if fit.max_px > 0.05:
        logger.warning("camera %r: Gazebo's image-normalised <distortion> has no exact OpenCV equivalent at %dx%d; "
                       "the fitted plumb_bob model differs by %.3f px RMS, %.3f px at worst",
                       spec.name, spec.width, spec.height, fit.rms_px, fit.max_px)
    return Distortion(model="plumb_bob", coefficients=fit.coefficients)


def _warn_crop(spec: CameraSpec, coeffs: tuple[float, ...], center: tuple[float, float], simulator: str | None) -> None:
    """Gazebo crops a barrel-distorted image (k1 < 0) to hide its black border: say how much that magnifies it, with
    the advice of the simulator the file is for (``None``: both)."""
    if simulator == "gazebo-classic" and spec.plugin is not None and not spec.plugin.border_crop:
        return
    mx, my = crop_magnification((coeffs[0], coeffs[1], coeffs[2], coeffs[3], coeffs[4]), center)
    if max(mx, my) > 1.0005:
        classic = "set <borderCrop>false</borderCrop> in its gazebo_ros camera plugin"
        fix = {"gazebo-classic": classic, "gz-sim": "gz-sim has no switch for it"}.get(
            simulator or "", f"in Gazebo classic {classic}; gz-sim has no switch for it")
        logger.warning("camera %r: Gazebo crops its barrel-distorted image (k1 < 0), magnifying it %.4f x %.4f: the "
                       "rendered focal lengths are that much larger than these (%s)", spec.name, mx, my, fix)


def renders_as_link(spec: CameraSpec, *, tol_rad: float = 1e-3) -> bool:
    """True when the rendered optical frame is the camera's link frame itself (same origin, axes within
    ``tol_rad``): then the link (typically ``*_optical``) is the frame the images belong to."""
    T = optical_pose(spec)
    cos_angle = (float(np.trace(T[:3, :3])) - 1.0) / 2.0
    return float(np.linalg.norm(T[:3, 3])) < 1e-9 and math.acos(max(-1.0, min(1.0, cos_angle))) < tol_rad


def _camera(spec: CameraSpec, convention: str, description: Description | None = None) -> Camera:
    k = intrinsics_for(spec.width, spec.height, spec.hfov_rad, convention, spec.lens)
    frame = spec.plugin.frame_name if spec.plugin and spec.plugin.frame_name else ""
    if spec.sensor_type == MJCF_SENSOR_TYPE:  # MuJoCo cameras have their own names; their optical frame is named so
        frame = f"{spec.name}_optical_frame"
    elif not frame.endswith(OPTICAL_SUFFIXES):
        frame = spec.link if renders_as_link(spec) else f"{spec.link}_optical_frame"
    return Camera(width_px=spec.width, height_px=spec.height, fx_px=k.fx, fy_px=k.fy, cx_px=k.cx, cy_px=k.cy,
                  skew=k.skew, distortion=_distortion(spec, k, convention, _simulator(spec, description, convention)),
                  frame_id=frame)


def _simulation(spec: CameraSpec) -> SimulationSettings:
    near = spec.clip_near_m if spec.clip_near_m is not None else DEFAULT_CLIP_M[0]
    far = spec.clip_far_m if spec.clip_far_m is not None else DEFAULT_CLIP_M[1]
    return SimulationSettings(clip_near_m=near, clip_far_m=far, update_rate_hz=spec.update_rate_hz or None,
                              noise_stddev=spec.noise.stddev if spec.noise else None)


def _included_sha256(path: Path, source: Path) -> str:
    """sha256 of an included file, read as every input is (regular file, bounded); SourceError when it changed."""
    try:
        return hashlib.sha256(read_regular_file(path, limit=MAX_TEXT_BYTES)).hexdigest()
    except (OSError, ValueError):
        raise SourceError(f"included file {path.name!r} changed while it was read", path=source, field="<include>",
                          hint="run again") from None


def _default_name(path: Path) -> str:
    stem = path.name.split(".")[0]
    return re.sub(r"[^A-Za-z0-9_.\-]", "_", stem) or "sim_rig"


def _extrinsics(pair: StereoPair, path: Path) -> Extrinsics:
    R, T = opencv_extrinsics_from_pose(pair.T_left_right)
    if float((T**2).sum()) < 1e-12:
        raise SourceError(f"cameras {pair.left.name!r} and {pair.right.name!r} are at the same place (zero "
                          "baseline)", path=path, field="<joint>/<pose>",
                          hint="move the right camera sideways, e.g. joint origin xyz='0 -0.1 0'")
    return Extrinsics(rotation=tuple(map(tuple, R.tolist())), translation_m=tuple(T.tolist()))  # type: ignore[arg-type]


def profile_from_pair(description: Description, pair: StereoPair, *, convention: str = "gazebo-classic",
                      name: str | None = None, xacro_args: Mapping[str, str] | None = None,
                      env: Mapping[str, str] | None = None, convention_why: str = "") -> StereoProfile:
    """The sim profile of an already chosen pair (see :func:`load_description_profile`); ``convention_why`` says
    how the convention was chosen when it was not given (provenance notes)."""
    source = description.path
    args = " ".join(f"{k}:={v}" for k, v in sorted((xacro_args or {}).items()))
    passed = " ".join(f"{k}={v}" for k, v in sorted((env or {}).items()))
    how = (f"intrinsics as MuJoCo renders them (left {pair.left.intrinsics_form}, right {pair.right.intrinsics_form}),"
           " exact pixel-centre convention" + ("" if pair.left.clip_near_m is not None else "; clip planes not read "
                                                "(MuJoCo scales <map znear zfar> by the model's extent)")
           if description.kind == "mjcf" else f"intrinsics from horizontal_fov in the {convention} convention")
    notes = "; ".join([f"cameras {pair.left.name!r} (left) and {pair.right.name!r} (right); {how}"
                       + (f"; xacro args {args}" if args else "") + (f"; --env {passed}" if passed else "")
                       + "".join(f"; {c.name}: {r}" for c in (pair.left, pair.right) for r in c.remarks),
                       *([f"pixel convention {convention} {convention_why}"] if convention_why else []),
                       *description.notes])
    sources = (SourceFile(path=str(source), sha256=sha256_file(source)),
               *(SourceFile(path=str(p), sha256=_included_sha256(p, source)) for p in description.included_files))
    command = "from-description" if description.kind == "mjcf" else "from-urdf"  # shipped profiles stay as built
    try:  # every model built here is validated (bounds of s2r.profile): a bad value is one SourceError
        left_cam = _camera(pair.left, convention, description)
        right_cam = _camera(pair.right, convention, description)
        extrinsics = _extrinsics(pair, source)
        baseline = float(sum(t * t for t in extrinsics.translation_m) ** 0.5)
        simulation = _simulation(pair.left)
        return StereoProfile(
            name=name or _default_name(source),
            description=f"{description.kind.upper()} stereo pair from {source.name} ({convention} convention)",
            left=left_cam, right=right_cam, extrinsics=extrinsics,
            matcher=seed_matcher(left_cam.fx_px, baseline, left_cam.width_px, far_limit_m=simulation.clip_far_m),
            simulation=simulation,
            provenance=Provenance(origin="sim", method=f"s2r profile {command} ({description.kind})",
                                  convention=convention, sources=sources, notes=notes),
        )
    except ValidationError as exc:
        first = exc.errors()[0]
        raise SourceError(f"the cameras do not make a valid profile: {first['msg']}", path=source,
                          field=".".join(str(p) for p in first["loc"]), hint="check the two camera sensors") from None
