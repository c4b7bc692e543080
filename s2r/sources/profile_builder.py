"""Sim profiles from robot descriptions: :func:`load_description_profile` reads a description, picks its stereo
pair, refuses a pair ``s2r lint`` calls an error (:mod:`s2r.sources.lint.geometry`), chooses the pixel convention
and builds the profile (:func:`s2r.sources.pair_profile.profile_from_pair`)."""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from pathlib import Path

from s2r.errors import SourceError
from s2r.profile import StereoProfile
from s2r.sources.conventions import check_convention
from s2r.sources.description import Description
from s2r.sources.lint.geometry import baseline_findings
from s2r.sources.loader import StereoPair, load_description, log_notes, stereo_pair
from s2r.sources.pair_profile import profile_from_pair

__all__ = ["choose_convention", "load_description_profile"]

logger = logging.getLogger(__name__)


def choose_convention(description: Description) -> tuple[str, str]:
    """The pixel convention of a description read without ``--convention``, and why (for the log and provenance):
    the simulator it loads plugins of (:mod:`s2r.sources.simulator`), else ``gazebo-classic`` (the default)."""
    guess = description.simulator
    if guess is not None and guess.simulator is not None:
        return guess.simulator, f"inferred from {guess.evidence}"
    if guess is not None and guess.evidence:
        return "gazebo-classic", f"assumed: the file loads {guess.evidence}"
    return "gazebo-classic", "assumed: the file loads no gz-sim system and no gazebo_ros plugin (the default)"


def load_description_profile(
    path: str | Path, *, convention: str | None = None, left: str | None = None, right: str | None = None,
    xacro_args: Mapping[str, str] | None = None, package_paths: Sequence[Path] = (), name: str | None = None,
    allow_bad_baseline: bool = False, env: Mapping[str, str] | None = None, keyframe: str | None = None,
) -> StereoProfile:
    """A sim :class:`StereoProfile` from a URDF / xacro / SDF file with two camera sensors, or an MJCF model with
    two cameras.

    Args:
        path: ``.urdf``, ``.xacro``, ``.urdf.xacro``, ``.sdf``, ``.world`` or MJCF (``<mujoco>``) file.
        convention: pixel convention of the intrinsics: ``gazebo-classic``, ``gz-sim`` or ``exact``; None (default)
            infers it from the simulator the file loads plugins of (:func:`choose_convention`), logs which and why,
            and records it in the provenance. MJCF: ``exact`` only (MuJoCo renders the exact pinhole, measured by
            rendering).
        keyframe: MJCF only: read the bodies at this ``<keyframe>`` (index or name) instead of the initial state.
        left, right: camera names (sensor, ``sensor/camera``, camera or link name) when not unambiguous.
        xacro_args: ``name:=value`` arguments of a xacro file.
        package_paths: folders searched for ``$(find pkg)`` before ``ROS_PACKAGE_PATH``.
        name: profile name (default: the file name up to its first dot).
        allow_bad_baseline: write a pair that ``s2r lint`` calls an error (baseline along the optical axis,
            right camera on the left) with a warning instead of refusing it.
        env: the values xacro's ``$(env NAME)`` / ``$(optenv NAME default)`` see (``--env NAME=VALUE``, e.g.
            Clearpath's ``JACKAL_BB2=1``); the machine's environment is never read. Recorded in the provenance.

    The optical axes come from the composed sensor poses (Gazebo renders along the camera frame's +x),
    never from link names. The pair's geometry follows the same rule as ``s2r lint``
    (:func:`s2r.geometry.baseline_layout_problem`): refused unless ``allow_bad_baseline``.

    Returns:
        Origin ``sim``; R, T in OpenCV's convention (metres); provenance with the convention and the source
        file's sha256; simulation settings from ``<clip>``, ``<update_rate>`` and ``<noise>``.
    """
    source = Path(path)
    if convention is not None:
        check_convention(convention)
    description = load_description(source, xacro_args=xacro_args, package_paths=package_paths, env=env,
                                   keyframe=keyframe)
    pair = stereo_pair(description, left=left, right=right)
    _check_geometry(description, pair, allow=allow_bad_baseline)
    why = ""
    if description.kind == "mjcf":
        convention = _mjcf_convention(description, convention)
    elif convention is None:
        convention, why = choose_convention(description)
    for camera in (pair.left, pair.right):
        for remark in camera.remarks:
            logger.warning("%s: camera %r: %s", description.path, camera.name, remark)
    profile = profile_from_pair(description, pair, convention=convention, name=name, xacro_args=xacro_args, env=env,
                                convention_why=why)
    log_notes(description)  # said once the profile stands: an error stays the only line
    if why:
        logger.warning("%s: pixel convention %s, %s (pass --convention to choose)", source, convention, why)
    return profile


def _mjcf_convention(description: Description, convention: str | None) -> str:
    """MuJoCo renders the exact pinhole (measured by rendering): only ``exact`` is accepted for an MJCF model."""
    if convention not in (None, "exact"):
        raise SourceError(f"--convention {convention} describes Gazebo's published camera_info; MuJoCo renders the "
                          "exact pinhole (optical axis at (W - 1) / 2 - principal offset)", path=description.path,
                          field="--convention", hint="leave --convention out (or pass exact) for an MJCF model")
    return "exact"


def _check_geometry(description: Description, pair: StereoPair, *, allow: bool) -> None:
    """Refuse (or, when ``allow``, warn about) what lint reports about the pair's baseline; warn on offsets."""
    for severity, code, message, fix, line, needles in baseline_findings(description, pair):
        if description.source_text != description.expanded_text:  # xacro: the first source line with a needle
            lines = description.source_text.splitlines()
            line = next((n for needle in needles for n, text in enumerate(lines, start=1) if needle in text), None)
        where = f"line {line}" if line else "<joint>/<pose>"
        if severity == "error" and not allow:
            sizes = _size_mismatch(pair)  # a second problem of the pair is named with the first, not a run later
            raise SourceError(f"[{code}] {message.split('; corrected:')[0]}" + (f"; and {sizes}" if sizes else ""),
                              path=description.path, field=where,
                              hint=f"{fix}" + ("; give both cameras one image size" if sizes else "")
                              + "; or pass --allow-bad-baseline to write it anyway (s2r lint says the same)")
        logger.warning("%s: %s: %s [%s] %s", description.path, where, severity.upper(), code, message)


def _size_mismatch(pair: StereoPair) -> str:
    """``"the cameras differ in image size: WxH vs WxH (...)"`` when they do, else ``""``."""
    left, right = pair.left, pair.right
    if (left.width, left.height) == (right.width, right.height):
        return ""
    return (f"the cameras differ in image size: {left.width}x{left.height} vs {right.width}x{right.height} "
            "(rectification needs one size)")
