"""MJCF ``<camera>`` intrinsics as MuJoCo renders them, in OpenCV's 0-based pixel-centre (``exact``) convention.

MuJoCo 3.2+ / 4.0 (src/user/user_objects.cc ``mjCCamera::Compile``, src/engine/engine_vis_visualize.c
``getFrustum``), for an image W x H pixels:

- ``fovy`` (the VERTICAL field of view, always degrees, default 45, below 180): ``fx = fy = (H / 2) / tan(fovy / 2)``,
  principal point at the image centre ``((W - 1) / 2, (H - 1) / 2)``.
- ``sensorsize`` (metres, both > 0) makes ``focal`` / ``focalpixel`` and ``principal`` / ``principalpixel`` active
  and ``fovy`` ignored; each pixel value wins over its length value per axis; lengths convert to pixels with the
  pixel density ``resolution / sensorsize``: ``fx = focal_x * W / sensorsize_x`` (or ``focalpixel_x``), likewise
  ``fy``, and the principal OFFSETS ``px``, ``py``. MuJoCo shifts its frustum by the offset, so the optical axis
  renders at ``cx = (W - 1) / 2 - px`` and ``cy = (H - 1) / 2 - py`` (both MINUS; pinned by rendering a point on the
  optical axis in tests/sources/test_mjcf_render.py).
- ``resolution`` (default ``1 1``: unset) is only a stored size: a camera without one renders at the offscreen
  buffer size ``<visual><global offwidth offheight>`` (default 640 x 480).

The camera frame looks along its -z with +y up; the OpenCV optical frame is that frame turned by pi about x.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass

from s2r.errors import SourceError
from s2r.profile import MAX_IMAGE_PX, MIN_IMAGE_PX
from s2r.sources.mjcf.pose import numbers, where
from s2r.sources.xmlparse import XmlDoc

__all__ = ["DEFAULT_OFFSCREEN", "MODES", "MjcfIntrinsics", "camera_intrinsics", "offscreen_size"]

#: ``<visual><global offwidth offheight>`` defaults, pixels.
DEFAULT_OFFSCREEN = (640, 480)
MODES = ("fixed", "track", "trackcom", "targetbody", "targetbodycom")
_INTRINSIC = ("focal", "focalpixel", "principal", "principalpixel")
_MAX_SENSOR_M = 1.0  # a sensor or focal length beyond 1 m is a unit mistake (millimetres written as metres)


@dataclass(frozen=True)
class MjcfIntrinsics:
    """Pinhole intrinsics (pixels, exact 0-based convention) of a W x H image and how they were derived."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    form: str
    resolution_given: bool


def _pair(doc: XmlDoc, camera: ET.Element, attrs: Mapping[str, str], name: str) -> tuple[float, float]:
    values = numbers(doc, camera, name, attrs.get(name, "0 0"), 2)
    return values[0], values[1]


def offscreen_size(doc: XmlDoc) -> tuple[int, int]:
    """``<visual><global offwidth offheight>`` (the last setting wins), pixels."""
    width, height = DEFAULT_OFFSCREEN
    for node in doc.root.iter("global"):
        for attr in ("offwidth", "offheight"):
            if attr in node.attrib:
                value = _whole(doc, node, attr, node.get(attr, ""))
                width, height = (value, height) if attr == "offwidth" else (width, value)
    return width, height


def _whole(doc: XmlDoc, element: ET.Element, attr: str, text: str, count: int = 1) -> int:
    values = numbers(doc, element, attr, text, count, limit=1e9)
    for v in values:
        if v != int(v) or not MIN_IMAGE_PX <= v <= MAX_IMAGE_PX:
            raise SourceError(f"{attr} must be whole pixels from {MIN_IMAGE_PX} to {MAX_IMAGE_PX}, got {text!r}",
                              path=doc.path, field=where(doc, element, attr), hint="no stereo camera has such a size")
    return int(values[0])


def _resolution(doc: XmlDoc, camera: ET.Element, attrs: Mapping[str, str]) -> tuple[int, int] | None:
    text = attrs.get("resolution")
    if text is None:
        return None
    values = numbers(doc, camera, "resolution", text, 2, limit=1e9)
    if values == (1.0, 1.0):
        return None  # MuJoCo's default: no stored size
    return _whole(doc, camera, "resolution", text, 2), int(values[1])


def _fovy(doc: XmlDoc, camera: ET.Element, attrs: Mapping[str, str]) -> float:
    fovy = numbers(doc, camera, "fovy", attrs.get("fovy", "45"), 1)[0]
    if not 0.0 < fovy < 180.0:
        raise SourceError(f"fovy {fovy:g} must be between 0 and 180 (degrees, always, whatever <compiler angle>)",
                          path=doc.path, field=where(doc, camera, "fovy"), hint="give the VERTICAL field of view "
                          "in degrees")
    return fovy


def _check_lengths(doc: XmlDoc, camera: ET.Element, attrs: Mapping[str, str]) -> None:
    for name in ("sensorsize", "focal", "focalpixel"):
        values = _pair(doc, camera, attrs, name)
        if any(v < 0 for v in values):
            raise SourceError(f"{name} must not be negative, got {attrs.get(name)!r}", path=doc.path,
                              field=where(doc, camera, name))
        if name != "focalpixel" and any(v > _MAX_SENSOR_M for v in values):
            raise SourceError(f"{name} {attrs.get(name)!r} is beyond {_MAX_SENSOR_M:g} m", path=doc.path,
                              field=where(doc, camera, name), hint="lengths are metres (a 6 mm sensor is 0.006)")


def _sensor_intrinsics(doc: XmlDoc, camera: ET.Element, attrs: Mapping[str, str], size: tuple[int, int],
                       stored: tuple[int, int]) -> tuple[float, float, float, float]:
    """fx, fy (pixels) and the principal offsets px, py (pixels) of a ``sensorsize`` camera rendered at ``size``."""
    sw, sh = _pair(doc, camera, attrs, "sensorsize")
    density = (stored[0] / sw, stored[1] / sh)  # MuJoCo: resolution / sensorsize, pixels per metre
    metres: list[float] = []
    for axis in (0, 1):
        for length, pixel in (("focal", "focalpixel"), ("principal", "principalpixel")):
            p = _pair(doc, camera, attrs, pixel)[axis]
            metres.append(p / density[axis] if p else _pair(doc, camera, attrs, length)[axis])
    fx_m, px_m, fy_m, py_m = metres
    if fx_m <= 0 or fy_m <= 0:
        raise SourceError("a camera with sensorsize needs a positive focal length in x and y", path=doc.path,
                          field=where(doc, camera, "focal"), hint="give focal (metres) or focalpixel (pixels)")
    scale = (size[0] / sw, size[1] / sh)
    return fx_m * scale[0], fy_m * scale[1], px_m * scale[0], py_m * scale[1]


def camera_intrinsics(doc: XmlDoc, camera: ET.Element, attrs: Mapping[str, str],
                      offscreen: tuple[int, int]) -> MjcfIntrinsics:
    """The intrinsics MuJoCo renders ``camera`` with (``attrs``: its attributes over its defaults class).

    Raises:
        SourceError: orthographic projection, fovy outside (0, 180), intrinsic attributes without sensorsize,
            pixel values without a resolution, negative or absurd values.
    """
    projection = attrs.get("projection", "perspective")
    if projection != "perspective":
        raise SourceError(f"projection {projection!r} is not a pinhole camera", path=doc.path,
                          field=where(doc, camera, "projection"), hint="stereo needs projection='perspective'")
    _check_lengths(doc, camera, attrs)
    stored = _resolution(doc, camera, attrs)
    size = stored or offscreen
    sensor = _pair(doc, camera, attrs, "sensorsize")
    used = [n for n in _INTRINSIC if any(_pair(doc, camera, attrs, n))]
    if used and not (sensor[0] > 0 and sensor[1] > 0):
        raise SourceError(f"{'/'.join(used)} need sensorsize (MuJoCo refuses the model)", path=doc.path,
                          field=where(doc, camera, used[0]), hint="add sensorsize='width height' in metres")
    if not (sensor[0] > 0 and sensor[1] > 0):
        fy = (size[1] / 2.0) / math.tan(math.radians(_fovy(doc, camera, attrs)) / 2.0)
        return MjcfIntrinsics(size[0], size[1], fy, fy, (size[0] - 1) / 2.0, (size[1] - 1) / 2.0, "fovy",
                              stored is not None)
    if stored is None and any(any(_pair(doc, camera, attrs, n)) for n in ("focalpixel", "principalpixel")):
        raise SourceError("focalpixel/principalpixel need a resolution (MuJoCo converts them with resolution / "
                          "sensorsize)", path=doc.path, field=where(doc, camera, "resolution"),
                          hint="add resolution='width height' in pixels")
    fx, fy, px, py = _sensor_intrinsics(doc, camera, attrs, size, stored or (1, 1))
    form = "sensorsize + " + " + ".join(used)
    return MjcfIntrinsics(size[0], size[1], fx, fy, (size[0] - 1) / 2.0 - px, (size[1] - 1) / 2.0 - py, form,
                          stored is not None)
