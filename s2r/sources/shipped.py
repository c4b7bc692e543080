"""The shipped sim profiles and the robot descriptions they are generated from.

Regenerate them with ``.venv/bin/s2r profile regenerate-sim`` (``--check`` only compares). The profiles
record their source path relative to the repository and a fixed ``created`` date
(:data:`SHIPPED_CREATED`) so that regenerating reproduces the shipped files byte for byte.
"""

from __future__ import annotations

from pathlib import Path

from s2r.profile import StereoProfile
from s2r.sources.profile_builder import load_description_profile

__all__ = ["REPO_ROOT", "SHIPPED", "SHIPPED_CREATED", "shipped_profiles"]

REPO_ROOT = Path(__file__).resolve().parents[2]
SHIPPED_CREATED = "2026-11-21"
#: profile file (relative to the repo) -> (description file relative to the repo, profile name)
SHIPPED: dict[str, tuple[str, str]] = {
    "profiles/sim/gazebo_dual_camera.yaml": ("urdf/dual_camera_fixed.urdf.xacro", "gazebo_dual_camera"),
    "profiles/sim/xbot_u_stereo.yaml": ("urdf/xbot_u_stereo.sdf", "xbot_u_stereo"),
}


def _shipped(source: str, name: str, root: Path) -> StereoProfile:
    profile = load_description_profile(root / source, name=name, convention="gazebo-classic")  # both gazebo_ros rigs
    sources = tuple(s.model_copy(update={"path": source}) for s in profile.provenance.sources)
    provenance = profile.provenance.model_copy(update={"sources": sources, "created": SHIPPED_CREATED})
    return profile.model_copy(update={"provenance": provenance})


def shipped_profiles(root: Path = REPO_ROOT) -> dict[Path, StereoProfile]:
    """Each shipped sim profile as generated now from its description, by absolute profile path."""
    return {root / out: _shipped(src, name, root) for out, (src, name) in SHIPPED.items()}
