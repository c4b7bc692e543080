"""Intel RealSense ``rs-enumerate-devices -c`` text: the two infrared streams of one resolution as a stereo pair.

The tool prints, per stream and resolution, ``Intrinsic of "Infrared 1" / 848x480 / {Y8}`` followed by
Width, Height, PPX, PPY, Fx, Fy, Distortion and Coeffs, and for every stream pair
``Extrinsic from "A" To "B"`` with a rotation matrix and a translation vector in metres.

Convention: librealsense's extrinsics map points from A's frame into B's, ``p_B = R p_A + t``, which
is OpenCV's ``X_right = R X_left + T`` with A = Infrared 1 (left) and B = Infrared 2 (right); a D435's
right imager 50 mm to the right prints ``Translation Vector: -0.05 0 0``. ``rs2_extrinsics.rotation``
is stored column-major; current rs-enumerate-devices prints it as the matrix (row ``i`` shows
``rotation[j*3 + i]``), while some old versions printed the storage order (the transpose). When the
reverse extrinsic (B to A) is printed too, the reading that makes the two consistent is used.
"""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from s2r.errors import FormatError
from s2r.formats._common import (
    as_float,
    build_camera,
    build_stereo,
    distortion_for,
    provenance_for,
    read_text,
    rotation_as_printed,
)
from s2r.profile import Camera, StereoProfile

__all__ = ["RealSenseExtrinsic", "RealSenseIntrinsic", "camera_from_intrinsic", "is_realsense_text", "load_realsense",
           "parse_realsense"]

log = logging.getLogger(__name__)
FloatArray = NDArray[np.float64]
DEFAULT_RESOLUTION = (848, 480)

_INTRINSIC = re.compile(r'Intrinsic of "(?P<name>[^"]+)"\s*/\s*(?P<w>\d+)\s*x\s*(?P<h>\d+)\s*/\s*\{(?P<fmt>[^}]*)\}')
_EXTRINSIC = re.compile(r'Extrinsic from "(?P<a>[^"]+)"\s*To\s*"(?P<b>[^"]+)"')
_FIELDS = ("Width", "Height", "PPX", "PPY", "Fx", "Fy", "Distortion", "Coeffs")


@dataclass(frozen=True)
class RealSenseIntrinsic:
    """One ``Intrinsic of`` block: stream name, size and formats, principal point and focal lengths (pixels)."""

    stream: str
    width: int
    height: int
    formats: str
    ppx: float
    ppy: float
    fx: float
    fy: float
    distortion: str
    coeffs: tuple[float, ...]
    line: int


@dataclass(frozen=True, eq=False)
class RealSenseExtrinsic:
    """One ``Extrinsic from A To B`` block: ``p_B = R p_A + t`` (R 3x3 as printed, t in metres)."""

    source: str
    target: str
    R: FloatArray
    t: FloatArray
    line: int


def is_realsense_text(text: str) -> bool:
    """True when ``text`` looks like ``rs-enumerate-devices -c`` output."""
    return bool(_INTRINSIC.search(text)) and "PPX" in text


def _numbers(text: str, path: Path, field: str) -> list[float]:
    out = []
    for token in text.split():
        try:
            out.append(float(token))
        except ValueError:
            raise FormatError(f"expected numbers, got {token!r}", path=path, field=field) from None
    return [as_float(v, path, field) for v in out]


def _intrinsic_block(lines: list[str], start: int, path: Path) -> RealSenseIntrinsic | None:
    head = _INTRINSIC.search(lines[start])
    assert head is not None
    if "NOT available" in "".join(lines[start + 1:start + 2]):
        return None
    values: dict[str, str] = {}
    for line in lines[start + 1:start + 12]:
        if not line.strip() or _INTRINSIC.search(line) or _EXTRINSIC.search(line):
            break
        key, _, value = line.partition(":")
        values[key.strip()] = value.strip()
    where = f'line {start + 1} "{head["name"]}" {head["w"]}x{head["h"]}'
    for key in _FIELDS:
        if key not in values:
            raise FormatError("field is missing", path=path, field=f"{where}: {key}")
    num = {key: _numbers(values[key], path, f"{where}: {key}") for key in ("Width", "Height", "PPX", "PPY", "Fx", "Fy")}
    if any(len(v) != 1 for v in num.values()):
        raise FormatError("expected one number per field", path=path, field=where)
    coeffs = _numbers(values["Coeffs"], path, f"{where}: Coeffs")
    if len(coeffs) != 5:
        raise FormatError(f"expected 5 coefficients, got {len(coeffs)}", path=path, field=f"{where}: Coeffs")
    width, height = int(num["Width"][0]), int(num["Height"][0])
    if (width, height) != (int(head["w"]), int(head["h"])):
        raise FormatError(f"Width/Height {width}x{height} disagree with the header", path=path, field=where)
    return RealSenseIntrinsic(
        stream=head["name"], width=width, height=height, formats=head["fmt"], ppx=num["PPX"][0],
        ppy=num["PPY"][0], fx=num["Fx"][0], fy=num["Fy"][0], distortion=values["Distortion"],
        coeffs=tuple(coeffs), line=start + 1,
    )


def _extrinsic_block(lines: list[str], start: int, path: Path) -> RealSenseExtrinsic | None:
    head = _EXTRINSIC.search(lines[start])
    assert head is not None
    where = f'line {start + 1} Extrinsic from "{head["a"]}" To "{head["b"]}"'
    body = [line for line in lines[start + 1:start + 9] if line.strip()]
    if not body or "N/A" in body[0]:
        return None
    if "Rotation" not in body[0] or len(body) < 5 or "Translation" not in body[4]:
        raise FormatError("expected a rotation matrix and a translation vector", path=path, field=where)
    rows = [_numbers(line, path, f"{where}: Rotation Matrix") for line in body[1:4]]
    if any(len(row) != 3 for row in rows):
        raise FormatError("expected 3 numbers per rotation row", path=path, field=f"{where}: Rotation Matrix")
    t = _numbers(body[4].partition(":")[2], path, f"{where}: Translation Vector")
    if len(t) != 3:
        raise FormatError(f"expected 3 numbers, got {len(t)}", path=path, field=f"{where}: Translation Vector")
    return RealSenseExtrinsic(source=head["a"], target=head["b"], R=np.array(rows), t=np.array(t), line=start + 1)


def parse_realsense(
    path: str | Path, *, streams: set[str] | None = None
) -> tuple[list[RealSenseIntrinsic], list[RealSenseExtrinsic]]:
    """The intrinsic and extrinsic blocks of an ``rs-enumerate-devices -c`` text file.

    Args:
        streams: read only blocks of these streams (others, e.g. a damaged Color block, are skipped);
            None reads every block.
    """
    source = Path(path)
    lines = read_text(source).splitlines()
    intrinsics: list[RealSenseIntrinsic] = []
    extrinsics: list[RealSenseExtrinsic] = []
    for index, line in enumerate(lines):
        head = _INTRINSIC.search(line)
        if head and (streams is None or head["name"] in streams):
            block = _intrinsic_block(lines, index, source)
            if block is not None:
                intrinsics.append(block)
        ext_head = _EXTRINSIC.search(line)
        if ext_head and (streams is None or {ext_head["a"], ext_head["b"]} <= streams):
            ext = _extrinsic_block(lines, index, source)
            if ext is not None:
                extrinsics.append(ext)
    if not intrinsics:
        wanted = "" if streams is None else f" of {', '.join(sorted(streams))}"
        raise FormatError(f'no "Intrinsic of" blocks{wanted} found', path=source,
                          hint="save the output of `rs-enumerate-devices -c` (with -c)")
    return intrinsics, extrinsics


def _pick(intrinsics: list[RealSenseIntrinsic], stream: str, size: tuple[int, int]) -> RealSenseIntrinsic:
    found = [i for i in intrinsics if i.stream == stream and (i.width, i.height) == size]
    preferred = [i for i in found if "Y8" in i.formats.split("/")]
    return (preferred or found)[0]


def _resolution(intrinsics: list[RealSenseIntrinsic], left: str, right: str, wanted: tuple[int, int] | None,
                path: Path) -> tuple[int, int]:
    sizes = {(i.width, i.height) for i in intrinsics if i.stream == left}
    both = sorted(sizes & {(i.width, i.height) for i in intrinsics if i.stream == right})
    listed = ", ".join(f"{w}x{h}" for w, h in both) or "none"
    if not both:
        raise FormatError(f'no resolution has both "{left}" and "{right}" intrinsics', path=path,
                          field=f'Intrinsic of "{left}"', hint="is this a stereo RealSense (D4xx)?")
    if wanted is not None:
        if wanted not in both:
            raise FormatError(f"resolution {wanted[0]}x{wanted[1]} not listed (available: {listed})", path=path,
                              field="--resolution")
        return wanted
    if DEFAULT_RESOLUTION in both or len(both) == 1:
        return DEFAULT_RESOLUTION if DEFAULT_RESOLUTION in both else both[0]
    raise FormatError(f"several resolutions listed ({listed})", path=path, field="--resolution",
                      hint="pick one with --resolution WIDTHxHEIGHT")


def camera_from_intrinsic(intr: RealSenseIntrinsic, path: Path, frame_id: str) -> Camera:
    """A :class:`Camera` from one stream's intrinsics: Brown Conrady (or none) as plumb_bob, Kannala Brandt4 as
    equidistant; other models refused unless every coefficient is zero. ``intr.line`` 0: not from a text file."""
    field = f'{f"line {intr.line} " if intr.line else ""}"{intr.stream}" {intr.width}x{intr.height}'
    model = intr.distortion.strip().lower()
    if model == "kannala brandt4":
        distortion = distortion_for("equidistant", intr.coeffs[:4], path, f"{field}: Coeffs")
    elif model in ("brown conrady", "none") or not any(intr.coeffs):
        distortion = distortion_for("plumb_bob", intr.coeffs, path, f"{field}: Coeffs")
    else:
        raise FormatError(f"distortion model {intr.distortion!r} is not supported", path=path,
                          field=f"{field}: Distortion", hint="s2r reads Brown Conrady and Kannala Brandt4")
    K = np.array([[intr.fx, 0.0, intr.ppx], [0.0, intr.fy, intr.ppy], [0.0, 0.0, 1.0]])
    return build_camera(K=K, size=(intr.width, intr.height), distortion=distortion, path=path, field=field,
                        frame_id=frame_id)


def _stereo_extrinsics(extrinsics: list[RealSenseExtrinsic], left: str, right: str,
                       path: Path) -> tuple[FloatArray, FloatArray]:
    """OpenCV ``(R, T)`` from the ``left -> right`` extrinsic, choosing the printed-or-transposed reading."""
    forward = next((e for e in extrinsics if (e.source, e.target) == (left, right)), None)
    if forward is None:
        raise FormatError("extrinsic block is missing", path=path, field=f'Extrinsic from "{left}" To "{right}"',
                          hint="save the full output of `rs-enumerate-devices -c`")
    field = f'line {forward.line} Extrinsic from "{left}" To "{right}": Rotation Matrix'
    R = rotation_as_printed(forward.R, path, field)
    reverse = next((e for e in extrinsics if (e.source, e.target) == (right, left)), None)
    if reverse is not None:
        as_printed = float(np.linalg.norm(reverse.t + R.T @ forward.t))
        transposed = float(np.linalg.norm(reverse.t + R @ forward.t))
        if transposed < 0.5 * as_printed:
            log.warning("%s: rotation printed in storage order (old librealsense); using its transpose", path)
            R = R.T
    return R, forward.t


def load_realsense(
    path: str | Path,
    *,
    resolution: tuple[int, int] | None = None,
    left: str = "Infrared 1",
    right: str = "Infrared 2",
    name: str | None = None,
    origin: str = "real",
) -> StereoProfile:
    """A stereo profile of a RealSense's two infrared imagers from ``rs-enumerate-devices -c`` text.

    Args:
        resolution: ``(width, height)``; default 848x480 (Intel's recommended depth mode) or the only one.
        left, right: the stream names of the left and right imagers (``Infrared_1`` / ``Infrared_2``, as newer
            librealsense prints them, or a T265's ``Fisheye 1`` / ``Fisheye 2`` are used when the file has no
            ``Infrared 1``).
    """
    source = Path(path)
    text = read_text(source)
    if (left, right) == ("Infrared 1", "Infrared 2") and f'"{left}"' not in text:
        for pair in (("Infrared_1", "Infrared_2"), ("Fisheye 1", "Fisheye 2"), ("Fisheye_1", "Fisheye_2")):
            if f'"{pair[0]}"' in text:  # newer librealsense: underscores; a T265 has two fisheye imagers
                left, right = pair
                break
    intrinsics, extrinsics = parse_realsense(source, streams={left, right})
    size = _resolution(intrinsics, left, right, resolution, source)
    kind = "fisheye" if left.lower().startswith("fisheye") else "infra"  # realsense2_camera's frame names
    lcam = camera_from_intrinsic(_pick(intrinsics, left, size), source, f"camera_{kind}1_optical_frame")
    rcam = camera_from_intrinsic(_pick(intrinsics, right, size), source, f"camera_{kind}2_optical_frame")
    R, T = _stereo_extrinsics(extrinsics, left, right, source)
    return build_stereo(
        name=name or f"realsense_{size[0]}x{size[1]}", left=lcam, right=rcam, R=R, T=T, path=source,
        provenance=provenance_for([source], "rs-enumerate-devices", origin=origin,
                                  notes="factory calibration of one unit, read from rs-enumerate-devices -c"),
        description=f'RealSense "{left}" + "{right}" at {size[0]}x{size[1]} (factory calibration)',
    )
