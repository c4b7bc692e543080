"""Helpers shared by the outside-format modules: strict number parsing, profile assembly, provenance.

Every helper turns bad input into a one-line :class:`FormatError` naming the file and the field, so
the format modules never leak a ``TypeError``, ``ValueError`` or pydantic ``ValidationError``.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ValidationError

from s2r.errors import FormatError
from s2r.fileio import read_text_file, sha256_file
from s2r.formats.s2r_yaml import validation_message
from s2r.geometry import ORTHONORMAL_TOL
from s2r.profile import (
    DISTORTION_COEFFICIENTS,
    Camera,
    Distortion,
    Extrinsics,
    Provenance,
    SourceFile,
    StereoProfile,
)
from s2r.safeparse import parse_yaml

__all__ = [
    "MAX_ABS_VALUE",
    "as_float",
    "as_int",
    "as_matrix",
    "build_camera",
    "build_stereo",
    "check_rotation_field",
    "distortion_for",
    "first_document",
    "printed_decimals",
    "provenance_for",
    "read_text",
    "read_yaml",
    "require",
    "rotation_as_printed",
]

FloatArray = NDArray[np.float64]
log = logging.getLogger(__name__)
#: Largest magnitude of any number in a calibration file: focal lengths stay below about 2e6 px and P[0,3]
#: (-fx B) below about 2e7 px m within s2r.profile's bounds; beyond 1e9 a value is corruption, and refusing
#: it here keeps later arithmetic free of overflow.
MAX_ABS_VALUE = 1e9


def read_text(path: str | Path) -> str:
    """The file's UTF-8 text; FormatError naming the file when it is missing or unreadable."""
    return read_text_file(path, error=FormatError)


def first_document(text: str) -> str:
    """The first non-empty YAML document of ``text`` (``rostopic echo`` separates messages with ``---``)."""
    docs: list[list[str]] = [[]]
    for line in text.splitlines():
        if line.strip() == "---":
            docs.append([])
        else:
            docs[-1].append(line)
    for doc in docs:
        if any(line.strip() and not line.lstrip().startswith("#") for line in doc):
            return "\n".join(doc)
    return ""


def read_yaml(text: str, path: str | Path) -> Any:
    """Parse YAML text (safe loader); FormatError with the line number when malformed."""
    return parse_yaml(text, path=path, error=FormatError)


def require(mapping: Any, key: str, path: str | Path, *, prefix: str = "") -> Any:
    """``mapping[key]``; FormatError naming the field when the mapping or the key is missing."""
    field = f"{prefix}{key}"
    if not isinstance(mapping, dict):
        where = prefix.rstrip(".") or "(top level)"
        raise FormatError("expected a mapping", path=path, field=where)
    if key not in mapping:
        raise FormatError("required field is missing (add it)", path=path, field=field)
    return mapping[key]


def as_float(value: Any, path: str | Path, field: str) -> float:
    """A finite float from a YAML/JSON scalar; bools, strings, NaN and inf are refused."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise FormatError(f"expected a number, got {type(value).__name__}", path=path, field=field)
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        raise FormatError(f"must be a finite number, got {number}", path=path, field=field)
    if abs(number) > MAX_ABS_VALUE:
        raise FormatError(f"{number:g} is beyond {MAX_ABS_VALUE:g} in magnitude: no calibration value is that large "
                          "(corrupted file or wrong units?)", path=path, field=field)
    return number


def as_int(value: Any, path: str | Path, field: str) -> int:
    """A positive integer (image sizes); FormatError naming the field otherwise."""
    number = as_float(value, path, field)
    if number != int(number) or number <= 0:
        raise FormatError(f"must be a positive whole number, got {value}", path=path, field=field)
    return int(number)


def as_matrix(value: Any, shape: tuple[int, ...], path: str | Path, field: str) -> FloatArray:
    """A finite float64 array of ``shape`` from a flat or nested list of numbers (the count is checked while
    walking, so a list that holds far more, or itself, is refused before it is expanded)."""
    expected = int(np.prod(shape))
    flat = _flatten(value, path, field, limit=expected)
    if len(flat) != expected:
        raise FormatError(f"expected {expected} numbers, got {len(flat)}", path=path, field=field)
    return np.array(flat, dtype=np.float64).reshape(shape)


#: Deepest list nesting a matrix field may have (a 3x3 matrix as rows is 2).
_MAX_NESTING = 8


def _flatten(value: Any, path: str | Path, field: str, *, limit: int) -> list[float]:
    """The numbers of a flat or nested list, in order; FormatError past ``limit`` numbers (or about four times
    as many items of any kind), past :data:`_MAX_NESTING` levels, or on a list that contains itself."""
    if isinstance(value, np.ndarray):
        if value.size > limit:
            raise FormatError(f"expected {limit} numbers, got {value.size}", path=path, field=field)
        value = value.tolist()
    if not isinstance(value, (list, tuple)):
        raise FormatError(f"expected a list of numbers, got {type(value).__name__}", path=path, field=field)
    out: list[float] = []
    budget = [4 * limit + 64]  # items visited, lists included: an alias bomb of empty lists has no numbers

    def walk(items: list[Any] | tuple[Any, ...], depth: int, on_path: frozenset[int]) -> None:
        if depth > _MAX_NESTING:
            raise FormatError(f"lists nested deeper than {_MAX_NESTING} levels", path=path, field=field)
        for item in items:
            budget[0] -= 1
            if budget[0] < 0 or len(out) > limit:
                raise FormatError(f"expected {limit} numbers, got more", path=path, field=field)
            if isinstance(item, (list, tuple)):
                if id(item) in on_path:
                    raise FormatError("a list that contains itself (a recursive YAML alias)", path=path,
                                      field=field)
                walk(item, depth + 1, on_path | {id(item)})
            else:
                out.append(as_float(item, path, field))

    walk(value, 1, frozenset({id(value)}))
    return out


def check_rotation_field(rot: FloatArray, path: str | Path, field: str) -> FloatArray:
    """Refuse a 3x3 matrix that is not a rotation (orthonormal, det +1, within ORTHONORMAL_TOL)."""
    err = float(np.max(np.abs(rot.T @ rot - np.eye(3))))
    if err > ORTHONORMAL_TOL:
        raise FormatError(
            f"not a rotation: max |R^T R - I| = {err:.2e} > {ORTHONORMAL_TOL:.0e}", path=path, field=field
        )
    det = float(np.linalg.det(rot))
    if abs(det - 1.0) > ORTHONORMAL_TOL:
        raise FormatError(f"not a rotation: determinant {det:.6f}, expected +1", path=path, field=field)
    return rot


def _digits(value: float) -> tuple[int, int]:
    """``(significant digits, decimal exponent)`` of the shortest text that reads back as ``value``: the float32
    text when ``value`` is exactly a float32 and that text is shorter (``dt: f`` matrices widened to float64)."""
    texts = [np.format_float_scientific(value, unique=True)]
    if float(np.float32(value)) == value:
        texts.append(np.format_float_scientific(np.float32(value), unique=True))
    best = (17, 0)
    for text in texts:
        mantissa, _, exponent = text.lower().partition("e")
        digits = mantissa.lstrip("-").replace(".", "").rstrip("0") or "0"
        best = min(best, (len(digits), int(exponent)))
    return best


def printed_decimals(values: FloatArray) -> int:
    """The most decimals any of ``values`` was printed with (17 when one needs full float precision)."""
    most = 0
    for value in np.asarray(values, dtype=np.float64).reshape(-1):
        significant, exponent = _digits(float(value))
        if value != 0:
            most = max(most, significant - 1 - exponent)
    return min(most, 17)


def _printed_units(values: FloatArray) -> FloatArray:
    """Per element, one unit in the last place ``values`` were printed with, under either way of printing.

    Files print a matrix with a fixed number of decimals d (``%.6f``: every element within 0.5e-d) or with s
    significant digits (``%g``, ORB-SLAM3's and Intel's files: each element within half a unit of its own s-th
    digit, 0.00445005 and 0.999983 alike). Neither the text nor the float tells which, so each element gets the
    larger of ``10^-d`` (d: the most decimals of any element) and ``10^(e - s + 1)`` (s: the most significant
    digits of any element, e: the element's own decimal exponent): a full unit, twice the rounding error.
    """
    array = np.asarray(values, dtype=np.float64)
    digits = [_digits(float(v)) for v in array.reshape(-1)]
    significant = max(s for s, _ in digits)
    fixed = 10.0 ** -printed_decimals(array)
    units = [max(fixed, 10.0 ** (e - significant + 1)) if v != 0 else fixed
             for v, (_, e) in zip(array.reshape(-1), digits, strict=True)]
    return np.array(units, dtype=np.float64).reshape(array.shape)


def _rotation_tolerance(rot: FloatArray) -> float:
    """Largest ``|R^T R - I|`` a rotation printed like ``rot`` can show from rounding alone (never below
    :data:`ORTHONORMAL_TOL`): ``sum_i |R_ij| u_ik + u_ij |R_ik|`` over the units ``u`` of :func:`_printed_units`,
    about 2e-6 for six significant digits."""
    units = _printed_units(rot)
    bound = np.abs(rot).T @ units + units.T @ np.abs(rot)
    return max(ORTHONORMAL_TOL, float(np.max(bound)))


def rotation_as_printed(rot: FloatArray, path: str | Path, field: str, *, zero_is_identity: bool = False) -> FloatArray:
    """A rotation read from text printed with limited precision: the nearest exact rotation (SVD) when
    ``|R^T R - I|`` is within what that precision explains (:func:`_rotation_tolerance`), refused (FormatError
    naming the field and the tolerance) beyond it.

    The result is orthonormal to float precision, so products of such rotations (``R2^T R1`` of a ROS pair)
    stay rotations. ``zero_is_identity``: an all-zero matrix (some ROS drivers publish R = 0 for an unrectified
    camera) is read as the identity with a warning.
    """
    if rot.shape != (3, 3):
        raise FormatError(f"expected a 3x3 rotation, got {rot.size} numbers in shape {rot.shape}", path=path,
                          field=field)
    if zero_is_identity and not np.any(rot):
        log.warning("%s: %s is all zeros; read as the identity (an unrectified camera)", path, field)
        return np.eye(3)
    err = float(np.max(np.abs(rot.T @ rot - np.eye(3))))
    tol = _rotation_tolerance(rot)
    if err > tol or float(np.linalg.det(rot)) <= 0:
        if err > tol:
            raise FormatError(f"not a rotation: max |R^T R - I| = {err:.2e}, beyond the {tol:.1e} its printed "
                              "precision explains", path=path, field=field,
                              hint="the matrix must be orthonormal to the digits it is printed with")
        return check_rotation_field(rot, path, field)  # raises: a reflection
    u, _, vt = np.linalg.svd(rot)
    fixed = np.asarray(u @ vt, dtype=np.float64)
    change = float(np.max(np.abs(fixed - rot)))
    if change > 1e-9:  # more than float noise: say so (a warning when a printed digit moves)
        level = logging.WARNING if change > 1e-4 else logging.INFO
        log.log(level, "%s: %s re-orthonormalised: max |R^T R - I| = %.2e, within the %.1e its printed precision "
                "explains (largest element change %.2e)", path, field, err, tol, change)
    return check_rotation_field(fixed, path, field)


def distortion_for(model: str, coeffs: Sequence[float], path: str | Path, field: str) -> Distortion:
    """A :class:`Distortion`, checking the coefficient count of ``model`` (an s2r model name)."""
    if model not in DISTORTION_COEFFICIENTS:
        known = ", ".join(DISTORTION_COEFFICIENTS)
        raise FormatError(f"unsupported distortion model {model!r} (supported: {known})", path=path, field=field)
    expected = DISTORTION_COEFFICIENTS[model]
    values = [float(c) for c in coeffs]
    if not values:
        values = [0.0] * expected  # an empty list means "no distortion" in ROS and Kalibr files
    if len(values) != expected:
        raise FormatError(
            f"distortion model {model} needs {expected} coefficients, got {len(values)}", path=path, field=field
        )
    distortion: Distortion = _validated(Distortion, {"model": model, "coefficients": tuple(values)}, path, field)
    return distortion


def _validated(model: type[BaseModel], data: dict[str, Any], path: str | Path, field: str) -> Any:
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        loc, msg = validation_message(exc)
        where = field if loc == "(top level)" else f"{field}.{loc}" if field else loc
        raise FormatError(msg, path=path, field=where) from None


def build_camera(
    *,
    K: FloatArray,
    size: tuple[int, int],
    distortion: Distortion,
    path: str | Path,
    field: str,
    frame_id: str = "",
) -> Camera:
    """A :class:`Camera` from a 3x3 K (pixels) and ``(width, height)``; FormatError naming ``field``."""
    if K[1, 0] != 0 or K[2, 0] != 0 or K[2, 1] != 0 or abs(K[2, 2] - 1.0) > 1e-9:
        raise FormatError(f"not a camera matrix: its last row must be [0 0 1] and K[1,0] 0, got K[2] = "
                          f"{K[2].tolist()}, K[1,0] = {K[1, 0]:g}", path=path, field=field,
                          hint="a pinhole K is [[fx s cx] [0 fy cy] [0 0 1]]")
    if K[0, 0] <= 0 or K[1, 1] <= 0:
        raise FormatError(
            f"focal length must be positive, got fx={K[0, 0]:g} fy={K[1, 1]:g}", path=path, field=field,
            hint="focal lengths are in pixels; all zeros means the camera was never calibrated",
        )
    width, height = size
    if not (0.0 <= K[0, 2] <= width and 0.0 <= K[1, 2] <= height):
        raise FormatError(
            f"principal point ({K[0, 2]:g}, {K[1, 2]:g}) lies outside the {width}x{height} image",
            path=path, field=field,
        )
    data = {
        "width_px": width, "height_px": height, "fx_px": float(K[0, 0]), "fy_px": float(K[1, 1]),
        "cx_px": float(K[0, 2]), "cy_px": float(K[1, 2]), "skew": float(K[0, 1]),
        "distortion": distortion.model_dump(), "frame_id": frame_id,
    }
    camera: Camera = _validated(Camera, data, path, field)
    return camera


def build_stereo(
    *,
    name: str,
    left: Camera,
    right: Camera,
    R: FloatArray,
    T: FloatArray,
    provenance: Provenance,
    path: str | Path,
    description: str = "",
) -> StereoProfile:
    """A :class:`StereoProfile` (OpenCV extrinsics, metres); FormatError naming the file on failure."""
    if left.image_size != right.image_size:
        raise FormatError(
            f"left and right image sizes differ ({left.width_px}x{left.height_px} vs "
            f"{right.width_px}x{right.height_px})", path=path, field="image size",
            hint="both cameras of a stereo pair must share one resolution",
        )
    extrinsics = _validated(
        Extrinsics, {"rotation": R.tolist(), "translation_m": T.tolist()}, path, "extrinsics"
    )
    safe_name = "".join(c if c.isalnum() or c in "_.-" else "_" for c in name) or "imported"
    data = {
        "name": safe_name, "description": description, "left": left.model_dump(), "right": right.model_dump(),
        "extrinsics": extrinsics.model_dump(), "provenance": provenance.model_dump(),
    }
    profile: StereoProfile = _validated(StereoProfile, data, path, "")
    return profile


def provenance_for(
    paths: Sequence[str | Path], fmt: str, *, origin: str = "real", notes: str = ""
) -> Provenance:
    """Provenance of an imported profile: origin, ``imported from <fmt>``, the sources with sha256."""
    if origin not in ("real", "sim", "nominal"):
        raise FormatError(f"origin must be real, sim or nominal, got {origin!r}", field="--origin")
    sources = tuple(SourceFile(path=str(p), sha256=sha256_file(p)) for p in paths)
    return Provenance(origin=origin, method=f"imported from {fmt}", sources=sources, notes=notes)  # type: ignore[arg-type]
