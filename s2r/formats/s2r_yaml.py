"""The canonical s2r profile YAML: the pydantic model as YAML, units in the key names.

Written atomically and never over an existing file unless ``force``. Loading turns every problem
(missing file, malformed YAML, unknown or invalid field) into a one-line :class:`ProfileError` that
names the file and the dotted field path.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, TypeVar

import yaml
from pydantic import BaseModel, ValidationError

from s2r.errors import ProfileError
from s2r.fileio import atomic_write_text, read_text_file
from s2r.profile import MonoProfile, StereoProfile
from s2r.safeparse import parse_yaml

__all__ = [
    "dump_profile",
    "load_mono_profile",
    "load_profile_file",
    "profile_from_mapping",
    "profile_to_yaml",
    "read_yaml_mapping",
    "validation_message",
]

ModelT = TypeVar("ModelT", bound=BaseModel)

_HEADER = (
    "# s2r stereo camera profile (schema_version 1).\n"
    "# Units are in the key names: _px pixels, _m metres, _hz hertz. Pixel coordinates are 0-based with\n"
    "# pixel centres at integers (OpenCV) unless provenance.convention says otherwise.\n"
    "# Extrinsics follow OpenCV: X_right = R @ X_left + T, in the left optical frame (z forward, x right).\n"
)


class _FlowListDumper(getattr(yaml, "CSafeDumper", yaml.SafeDumper)):  # type: ignore[misc]
    """Writes lists of scalars inline (``[1.0, 0.0]``) and everything else in block style.

    libyaml's emitter where PyYAML has it (its wheels do); the pure-Python one took 10 ms of a calibration's
    serial tail for one profile. The text is the same but for double-quoted strings (non-ASCII, control
    characters) longer than the line width, which libyaml keeps on one line where the pure-Python emitter
    folds them; both load back to the same profile."""


def _represent_list(dumper: yaml.SafeDumper, data: list[Any]) -> yaml.Node:
    flow = all(not isinstance(item, dict) for item in data) and len(data) <= 9
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


_FlowListDumper.add_representer(list, _represent_list)


def validation_message(exc: ValidationError) -> tuple[str, str]:
    """First pydantic error as ``(dotted.field.path, message)``, with a fix for unknown fields."""
    err = exc.errors()[0]
    loc = ".".join(str(part) for part in err["loc"]) or "(top level)"
    msg = str(err["msg"]).removeprefix("Value error, ")
    if err["type"] == "extra_forbidden":
        msg = "unknown field (remove it or check its spelling)"
    elif err["type"] == "missing":
        msg = "required field is missing (add it)"
    return loc, msg


def read_yaml_mapping(path: str | Path) -> dict[str, Any]:
    """Read a YAML file that must hold a mapping; raise ProfileError naming the file otherwise."""
    source = Path(path)
    data = parse_yaml(read_text_file(source, error=ProfileError), path=source, error=ProfileError)
    if not isinstance(data, dict):
        raise ProfileError("expected a YAML mapping at the top level", path=source, hint="is this a profile file?")
    return data


def profile_from_mapping(data: dict[str, Any], model: type[ModelT], *, path: str | Path | None = None) -> ModelT:
    """Validate a mapping into ``model``; ProfileError names the file and field path on failure."""
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        loc, msg = validation_message(exc)
        raise ProfileError(msg, path=path, field=loc) from None


def load_profile_file(path: str | Path) -> StereoProfile:
    """Load an s2r stereo profile YAML file."""
    data = read_yaml_mapping(path)
    if "camera" in data and "left" not in data:
        raise ProfileError(
            "this is a mono (camera-only) profile; a stereo profile is needed here", path=path,
            hint="calibrate both cameras without --mono",
        )
    return profile_from_mapping(data, StereoProfile, path=path)


def load_mono_profile(path: str | Path) -> MonoProfile:
    """Load an s2r mono (camera-only) profile YAML file."""
    return profile_from_mapping(read_yaml_mapping(path), MonoProfile, path=path)


def profile_to_yaml(profile: StereoProfile | MonoProfile) -> str:
    """The profile as s2r YAML text (with a header comment stating units and conventions)."""
    data = profile.model_dump(mode="json", exclude_none=True)
    return _HEADER + yaml.dump(data, Dumper=_FlowListDumper, sort_keys=False, width=110)


def dump_profile(profile: StereoProfile | MonoProfile, path: str | Path, *, force: bool = False) -> Path:
    """Write ``profile`` to ``path`` atomically; refuse to overwrite unless ``force``."""
    return atomic_write_text(path, profile_to_yaml(profile), force=force)
