"""Profile names -> files: ``S2R_PROFILE_PATH`` folders first, then the shipped ``profiles/``.

``S2R_PROFILE`` names the default profile used when downstream code asks for none.
"""

from __future__ import annotations

import os
from pathlib import Path

from s2r.errors import ProfileError
from s2r.formats.detect import load_any
from s2r.profile import StereoProfile

__all__ = ["PROFILE_ENV", "PROFILE_PATH_ENV", "SHIPPED_PROFILES", "list_profiles", "load_profile", "resolve_profile"]

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
            raise ProfileError("file not found", path=path, hint="check the path")
        return path
    known = list_profiles()
    if text not in known:
        names = ", ".join(sorted(known)) or "none"
        raise ProfileError(f"unknown profile name {text!r}; known profiles: {names}",
                           hint=f"pass a file path or add a folder to {PROFILE_PATH_ENV}")
    return known[text]


def load_profile(name_or_path: str | Path | None = None) -> StereoProfile:
    """Load a stereo profile by name, path, or (with no argument) the ``S2R_PROFILE`` default.

    Returns a :class:`StereoProfile` with ``.left.K``, ``.left.D``, ``.right.K``, ``.right.D``, ``.R``,
    ``.T`` (OpenCV convention, metres), ``.baseline_m`` and ``.image_size`` ``(width, height)``.
    A path may be any format :func:`s2r.formats.detect.load_any` reads from one file (s2r YAML, Kalibr,
    OpenCV FileStorage with R and T, rs-enumerate-devices text, a folder with ROS left.yaml/right.yaml).
    """
    return load_any(resolve_profile(name_or_path))
