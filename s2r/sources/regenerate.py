"""Regenerate the shipped sim profiles from the shipped robot descriptions.

    .venv/bin/python -m s2r.sources.regenerate          # rewrite profiles/sim/*.yaml
    .venv/bin/python -m s2r.sources.regenerate --check  # exit 1 if a shipped file is out of date

The profiles record their source path relative to the repository and a fixed ``created`` date
(:data:`SHIPPED_CREATED`) so that regenerating reproduces the shipped files byte for byte.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from s2r.fileio import atomic_write_text
from s2r.formats.s2r_yaml import profile_to_yaml
from s2r.profile import StereoProfile
from s2r.sources.profile_builder import load_description_profile

__all__ = ["REPO_ROOT", "SHIPPED", "SHIPPED_CREATED", "main", "shipped_profile_texts"]

REPO_ROOT = Path(__file__).resolve().parents[2]
SHIPPED_CREATED = "2026-11-21"
#: profile file (relative to the repo) -> (description file, profile name)
SHIPPED: dict[str, tuple[str, str]] = {
    "profiles/sim/gazebo_dual_camera.yaml": ("urdf/dual_camera_fixed.urdf.xacro", "gazebo_dual_camera"),
    "profiles/sim/xbot_u_stereo.yaml": ("urdf/xbot_u_stereo.sdf", "xbot_u_stereo"),
}


def _shipped(source: str, name: str, root: Path) -> StereoProfile:
    profile = load_description_profile(root / source, name=name)
    sources = tuple(s.model_copy(update={"path": source}) for s in profile.provenance.sources)
    provenance = profile.provenance.model_copy(update={"sources": sources, "created": SHIPPED_CREATED})
    return profile.model_copy(update={"provenance": provenance})


def shipped_profile_texts(root: Path = REPO_ROOT) -> dict[Path, str]:
    """The YAML text each shipped sim profile should hold, by absolute path."""
    return {root / out: profile_to_yaml(_shipped(src, name, root)) for out, (src, name) in SHIPPED.items()}


def main(argv: Sequence[str] | None = None) -> int:
    """Write (or with ``--check`` compare) the shipped sim profiles; returns the exit code."""
    parser = argparse.ArgumentParser(prog="python -m s2r.sources.regenerate", description=__doc__.split("\n")[0])
    parser.add_argument("--check", action="store_true", help="only compare; exit 1 when a file is out of date")
    args = parser.parse_args(argv)
    stale = 0
    for path, text in shipped_profile_texts().items():
        current = path.read_text(encoding="utf-8") if path.exists() else None
        if current == text:
            continue
        stale += 1
        if not args.check:
            atomic_write_text(path, text, force=True)
        print(f"{'stale' if args.check else 'wrote'} {path.relative_to(REPO_ROOT)}")
    return 1 if args.check and stale else 0


if __name__ == "__main__":
    sys.exit(main())
