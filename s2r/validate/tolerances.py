"""Validation tolerances: sensible defaults, overridable from a YAML file of ``key: number`` pairs.

Each tolerance is a limit on a difference (sim vs real) or an error (recovered vs declared, measured depth
vs theory). Units are in the key names: ``_px`` pixels, ``_m`` metres, ``_deg`` degrees, ``_rel`` a fraction
of the reference value, ``_pct`` percentage points, ``_sigma`` multiples of a standard deviation.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from s2r.errors import ValidateError
from s2r.fileio import read_text_file
from s2r.safeparse import parse_yaml

__all__ = ["Tolerances", "load_tolerances"]


@dataclass(frozen=True)
class Tolerances:
    """Limits used by the verdict (all non-negative numbers).

    Parameters (sim vs real): ``size_px`` largest allowed width/height difference; ``focal_rel`` fx, fy as a
    fraction of the real value; ``principal_point_px`` cx, cy; ``fov_deg`` horizontal and vertical field of
    view; ``distortion_abs`` largest coefficient difference; ``baseline_rel`` baseline as a fraction;
    ``rotation_deg`` angle between the two inter-camera rotations; ``depth_limit_rel`` the 2 % depth
    distance as a fraction. ``sigma`` is the multiple of the real profile's std that flags a difference
    as significant.

    Projection: ``projection_p95_px`` limit on the 95th percentile pixel shift at ``working_distance_m``.

    Recovered calibration (renderer + calibration chain on each profile): a recovered value passes when
    within ``recovery_sigma`` predicted standard deviations OR within the floor (``recovery_focal_rel``,
    ``recovery_pp_px``, ``recovery_baseline_rel``, ``recovery_rotation_deg``), the floor covering the
    renderer's known sub-pixel corner bias.

    Depth accuracy: sim vs real per distance bin, ``depth_gap_pct`` limit on the difference in median
    absolute relative error (percentage points) and ``fill_gap`` on the difference in fill rate; each
    profile's median absolute relative error must stay under ``depth_theory_factor`` times the theoretical
    RMS (Intel's model) at the bin's far end plus ``depth_floor_pct``, and its fill rate above ``min_fill``.

    Recordings (``--recording`` / ``--sim-recording``): per bin, Z accuracy and plane-fit RMS within
    ``depth_gap_pct`` points, fill rate within ``fill_gap``, sub-pixel RMS within ``subpixel_gap_rel`` of the real
    value.
    """

    size_px: float = 0.0
    focal_rel: float = 0.01
    principal_point_px: float = 2.0
    fov_deg: float = 1.0
    distortion_abs: float = 0.01
    baseline_rel: float = 0.02
    rotation_deg: float = 0.2
    depth_limit_rel: float = 0.10
    sigma: float = 3.0
    projection_p95_px: float = 1.0
    working_distance_m: float = 2.0
    recovery_sigma: float = 3.0
    recovery_focal_rel: float = 0.003
    recovery_pp_px: float = 1.5
    recovery_baseline_rel: float = 0.005
    recovery_rotation_deg: float = 0.2
    depth_gap_pct: float = 1.0
    fill_gap: float = 0.15
    depth_theory_factor: float = 3.0
    depth_floor_pct: float = 0.5
    min_fill: float = 0.5
    subpixel_gap_rel: float = 0.2

    @classmethod
    def valid_keys(cls) -> list[str]:
        """Every valid tolerance key, in declaration order."""
        return [f.name for f in dataclasses.fields(cls)]

    def as_dict(self) -> dict[str, float]:
        """The tolerances as a plain ``{key: value}`` mapping."""
        return dataclasses.asdict(self)


def _read_mapping(path: Path) -> dict[str, Any]:
    data = parse_yaml(read_text_file(path, error=ValidateError), path=path, error=ValidateError)
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ValidateError("expected a mapping of tolerance keys to numbers", path=path,
                            hint="write one 'key: number' per line")
    return data


def load_tolerances(path: str | Path | None = None, **overrides: float) -> Tolerances:
    """The default tolerances updated from a YAML file (``key: number``) and keyword ``overrides``.

    Raises:
        ValidateError: unreadable file, unknown keys (the message lists the valid ones), values that are
            not finite non-negative numbers.
    """
    data: dict[str, Any] = {} if path is None else _read_mapping(Path(path))
    data.update(overrides)
    where = None if path is None else Path(path)
    valid = Tolerances.valid_keys()
    unknown = sorted(str(k) for k in data if k not in valid)
    if unknown:
        raise ValidateError(f"unknown tolerance key(s) {', '.join(unknown)}; valid keys: {', '.join(valid)}",
                            path=where, hint="fix the spelling or remove them")
    clean: dict[str, float] = {}
    for key, value in data.items():
        ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value >= 0
        if not ok:
            raise ValidateError(f"must be a finite non-negative number, got {value!r}", path=where, field=key)
        clean[key] = float(value)
    if clean.get("working_distance_m", 1.0) <= 0:
        raise ValidateError("must be positive", path=where, field="working_distance_m")
    return dataclasses.replace(Tolerances(), **clean)
