"""Profile names -> files: ``S2R_PROFILE_PATH`` folders first, then the shipped ``profiles/``.

``S2R_PROFILE`` names the default profile used when downstream code asks for none.
"""

from __future__ import annotations

import difflib
import os
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

from s2r.errors import ProfileError
from s2r.fileio import protect_input

if TYPE_CHECKING:  # listing and resolving names needs neither the formats nor the profile models
    from s2r.profile import StereoProfile

__all__ = ["PROFILE_ENV", "PROFILE_PATH_ENV", "SHIPPED_PROFILES", "did_you_mean", "list_profiles", "load_profile",
           "resolve_profile"]

PROFILE_ENV = "S2R_PROFILE"
PROFILE_PATH_ENV = "S2R_PROFILE_PATH"
#: The profiles shipped with s2r (``profiles/sim``, ``profiles/real``) beside the package.
SHIPPED_PROFILES = Path(__file__).resolve().parent.parent / "profiles"
_SUFFIXES = (".yaml", ".yml")


def _search_dirs() -> list[Path]:
    extra = [Path(p) for p in os.environ.get(PROFILE_PATH_ENV, "").split(os.pathsep) if p]
    return [*extra, SHIPPED_PROFILES]


def list_profiles() -> dict[str, Path]:
    """Every profile name reachable by name, mapped to its file (earlier search folders win)."""
    found: dict[str, Path] = {}
    for folder in _search_dirs():
        if not folder.is_dir():
            continue
        for path in sorted(folder.rglob("*")):
            if path.suffix in _SUFFIXES and path.is_file():
                found.setdefault(path.stem, path)
    return found


def _looks_like_path(text: str) -> bool:
    return os.sep in text or "/" in text or text.endswith(_SUFFIXES) or Path(text).exists()


def resolve_profile(name_or_path: str | Path | None = None) -> Path:
    """The file behind a profile name or path (``None``: the ``S2R_PROFILE`` default)."""
    if name_or_path is None:
        name_or_path = os.environ.get(PROFILE_ENV)
        if not name_or_path:
            raise ProfileError(
                "no profile given", field=PROFILE_ENV, hint=f"pass a profile name or set {PROFILE_ENV}"
            )
    text = str(name_or_path)
    if isinstance(name_or_path, Path) or _looks_like_path(text):
        path = Path(text)
        if not path.exists():
            guess = did_you_mean(path.stem, list_profiles()) if len(path.parts) == 1 else ""
            raise ProfileError("file not found" + (guess if "did you mean" in guess else ""), path=path,
                               hint="check the path")
        return path
    known = list_profiles()
    if text not in known:
        raise ProfileError(f"unknown profile name {text!r}{did_you_mean(text, known)}",
                           hint=f"`s2r profile list` shows them all; pass a file path or add a folder to "
                           f"{PROFILE_PATH_ENV}")
    protect_input(known[text])  # found by name: --force must not write over it or replace its folder
    return known[text]


def did_you_mean(name: str, known: Iterable[str]) -> str:
    """``"; did you mean 'x'?"`` for the closest known names (difflib, case-insensitive), else the known names."""
    names = sorted(known)
    lowered = {n.lower(): n for n in names}
    close = [lowered[m] for m in difflib.get_close_matches(name.lower(), list(lowered), n=1, cutoff=0.6)]
    if not close:  # a unique prefix or substring ("d435", "gazebo") is as good a guess
        close = [n for n in names if name.lower() in n.lower()][:3]
    if close:
        return "; did you mean " + " or ".join(repr(n) for n in close) + "?"
    return f"; known profiles: {', '.join(names) or 'none'}"


def load_profile(name_or_path: str | Path | None = None) -> StereoProfile:
    """Load a stereo profile by name, path, or (with no argument) the ``S2R_PROFILE`` default.

    Returns a :class:`StereoProfile` with ``.left.K``, ``.left.D``, ``.right.K``, ``.right.D``, ``.R``,
    ``.T`` (OpenCV convention, metres), ``.baseline_m`` and ``.image_size`` ``(width, height)``.
    A path may be any format :func:`s2r.formats.detect.load_any` reads from one file (s2r YAML, Kalibr,
    OpenCV FileStorage with R and T, rs-enumerate-devices text, a folder with ROS left.yaml/right.yaml).
    """
    path = resolve_profile(name_or_path)
    if path.resolve().is_relative_to(SHIPPED_PROFILES.resolve()):
        from s2r.formats.s2r_yaml import load_profile_file  # shipped profiles are s2r YAML: no format detection

        return load_profile_file(path)
    from s2r.formats.detect import load_any

    return load_any(path)
