"""Camera ``<sensor>`` blocks (URDF ``<gazebo>`` extensions and SDF links) to :class:`CameraSpec` objects.

Reads the sensor ``<pose>``, ``<update_rate>``, every ``<camera>`` (with its own ``<pose>``,
``<horizontal_fov>``, ``<image>``, ``<clip>``, ``<noise>``, ``<distortion>``, ``<lens><intrinsics>``) and
the gazebo_ros plugin's ``hackBaseline`` / ``focalLength`` / ``frameName`` (ROS 1 and ROS 2 spellings).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np

from s2r.errors import SourceError
from s2r.geometry import make_transform, rotation_from_rpy
from s2r.profile import MAX_IMAGE_PX, MIN_IMAGE_PX
from s2r.sources.description import (
    CameraSpec,
    FloatArray,
    GazeboDistortion,
    LensIntrinsics,
    NoiseSpec,
    PluginSpec,
)
from s2r.sources.xmlparse import XmlDoc

__all__ = ["CAMERA_SENSOR_TYPES", "camera_specs", "parse_pose", "read_float"]

#: Largest pose coordinate accepted, metres or radians: 1000 km is beyond any robot or world file, and
#: keeps transforms far from float overflow (a joint at 1e308 m).
MAX_POSE_VALUE = 1e6
CAMERA_SENSOR_TYPES = frozenset({"camera", "multicamera", "depth", "depth_camera", "rgbd_camera", "rgbd"})


def _where(doc: XmlDoc, element: ET.Element) -> str:
    line = doc.line(element)
    return f"<{element.tag}>" + (f" line {line}" if line else "")


def read_float(doc: XmlDoc, element: ET.Element | None, default: float | None = None) -> float | None:
    """The float text of ``element`` (``default`` when absent); SourceError naming it when not a number."""
    if element is None or element.text is None or not element.text.strip():
        return default
    try:
        value = float(element.text.strip())
    except ValueError:
        raise SourceError(f"expected a number, got {element.text.strip()!r}", path=doc.path,
                          field=_where(doc, element), hint="write a plain decimal number") from None
    if not math.isfinite(value):
        raise SourceError("expected a finite number", path=doc.path, field=_where(doc, element))
    return value


def _floats(doc: XmlDoc, element: ET.Element, text: str | None, count: int) -> list[float]:
    parts = (text or "").split()
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise SourceError(f"expected {count} numbers, got {(text or '')[:80]!r}", path=doc.path,
                          field=_where(doc, element), hint=f"write {count} space-separated numbers")
    if any(abs(v) > MAX_POSE_VALUE for v in values):
        raise SourceError(f"a value beyond {MAX_POSE_VALUE:g} (metres or radians) in {(text or '')[:80]!r}",
                          path=doc.path, field=_where(doc, element), hint="poses are metres and radians")
    return values


def _positive(doc: XmlDoc, element: ET.Element | None, value: float | None, what: str, *,
              zero_ok: bool = False) -> float | None:
    """``value`` when absent or positive (or zero if ``zero_ok``); SourceError naming ``element`` otherwise."""
    if value is not None and element is not None and (value < 0 or (value == 0 and not zero_ok)):
        raise SourceError(f"{what} must be {'zero or ' if zero_ok else ''}positive, got {value:g}", path=doc.path,
                          field=_where(doc, element))
    return value


def parse_pose(doc: XmlDoc, element: ET.Element | None) -> FloatArray:
    """4x4 transform of a ``<pose>x y z roll pitch yaw</pose>`` (metres, radians, fixed axes xyz)."""
    if element is None:
        return np.eye(4)
    values = _floats(doc, element, element.text, 6)
    return make_transform(rotation_from_rpy(values[3:]), values[:3])


def parse_origin(doc: XmlDoc, element: ET.Element | None) -> FloatArray:
    """4x4 transform of a URDF ``<origin xyz="..." rpy="..."/>`` (both default to zero)."""
    if element is None:
        return np.eye(4)
    xyz = _floats(doc, element, element.get("xyz", "0 0 0"), 3)
    rpy = _floats(doc, element, element.get("rpy", "0 0 0"), 3)
    return make_transform(rotation_from_rpy(rpy), xyz)


def _lens(doc: XmlDoc, camera: ET.Element) -> LensIntrinsics | None:
    node = camera.find("lens/intrinsics")
    if node is None:
        return None
    values = {k: read_float(doc, node.find(k)) for k in ("fx", "fy", "cx", "cy", "s")}
    for k in ("fx", "fy"):
        _positive(doc, node.find(k), values[k], f"<lens><intrinsics><{k}> (focal length in pixels)")
    if any(values[k] is None for k in ("fx", "fy", "cx", "cy")):
        raise SourceError("<lens><intrinsics> needs fx, fy, cx and cy", path=doc.path, field=_where(doc, node),
                          hint="add the missing elements or remove <intrinsics>")
    return LensIntrinsics(fx=values["fx"] or 0.0, fy=values["fy"] or 0.0, cx=values["cx"] or 0.0,
                          cy=values["cy"] or 0.0, s=values["s"] or 0.0, line=doc.line(node))


def _distortion(doc: XmlDoc, camera: ET.Element) -> GazeboDistortion | None:
    node = camera.find("distortion")
    if node is None:
        return None
    k = {name: read_float(doc, node.find(name), 0.0) or 0.0 for name in ("k1", "k2", "k3", "p1", "p2")}
    center_node = node.find("center")
    center = (0.5, 0.5) if center_node is None else tuple(_floats(doc, center_node, center_node.text, 2))
    mode = next((c for c in node if c.tag.rsplit(":", 1)[-1].rsplit("}", 1)[-1] == "legacy_mode"), None)
    legacy = mode is None or (mode.text or "").strip().lower() not in ("false", "0")
    return GazeboDistortion(center=(center[0], center[1]), line=doc.line(node), legacy_mode=legacy, **k)


def _noise(doc: XmlDoc, camera: ET.Element) -> NoiseSpec | None:
    node = camera.find("noise")
    if node is None:
        return None
    return NoiseSpec(type=(node.findtext("type") or "gaussian").strip(),
                     mean=read_float(doc, node.find("mean"), 0.0) or 0.0,
                     stddev=read_float(doc, node.find("stddev"), 0.0) or 0.0)


def _plugin(doc: XmlDoc, sensor: ET.Element) -> PluginSpec | None:
    node = next((p for p in sensor.findall("plugin") if "camera" in (p.get("filename") or "")), None)
    if node is None:
        return None

    def first(*names: str) -> ET.Element | None:
        return next((node.find(n) for n in names if node.find(n) is not None), None)

    hack, focal = first("hackBaseline", "hack_baseline"), first("focalLength", "focal_length")
    frame, name = first("frameName", "frame_name"), first("cameraName", "camera_name")
    crop = first("borderCrop", "border_crop")
    return PluginSpec(
        border_crop=crop is None or (crop.text or "").strip().lower() not in ("false", "0"),
        filename=node.get("filename", ""), line=doc.line(node),
        hack_baseline=read_float(doc, hack), hack_baseline_line=doc.line(hack),
        hack_baseline_tag="" if hack is None else hack.tag,
        focal_length=read_float(doc, focal), focal_length_line=doc.line(focal),
        frame_name=None if frame is None else (frame.text or "").strip() or None,
        camera_name=None if name is None else (name.text or "").strip() or None,
    )


def _image_size(doc: XmlDoc, camera: ET.Element, field: str) -> int:
    node = camera.find(f"image/{field}")
    value = read_float(doc, node, 320.0 if field == "width" else 240.0)
    if value is None or value != int(value) or not MIN_IMAGE_PX <= value <= MAX_IMAGE_PX:
        raise SourceError(f"image {field} must be a whole number of pixels from {MIN_IMAGE_PX} to {MAX_IMAGE_PX}, "
                          f"got {value:g}" if value is not None else f"image {field} is empty", path=doc.path,
                          field=_where(doc, node if node is not None else camera),
                          hint="no stereo camera has a smaller or larger image")
    return int(value)


def _one_camera(doc: XmlDoc, sensor: ET.Element, camera: ET.Element, link: str, index: int,
                count: int) -> CameraSpec:
    sensor_name = sensor.get("name", "") or f"sensor_line_{doc.line(sensor)}"
    camera_name = camera.get("name", "") or ""
    name = sensor_name if count == 1 else f"{sensor_name}/{camera_name or index}"
    hfov_node = camera.find("horizontal_fov")
    if hfov_node is not None and not (hfov_node.text or "").strip():
        raise SourceError("<horizontal_fov> is empty", path=doc.path, field=_where(doc, hfov_node),
                          hint="give the field of view in radians, or remove the element for Gazebo's 1.047")
    hfov = read_float(doc, hfov_node, 1.047)
    assert hfov is not None
    if not 0.0 < hfov < math.pi:
        raise SourceError(f"horizontal_fov {hfov} rad is outside (0, pi)", path=doc.path,
                          field=_where(doc, camera if hfov_node is None else hfov_node),
                          hint="give the field of view in radians")
    clip = camera.find("clip")
    near_node, far_node = (None, None) if clip is None else (clip.find("near"), clip.find("far"))
    near = _positive(doc, near_node, read_float(doc, near_node), "<clip><near> (metres)")
    far = _positive(doc, far_node, read_float(doc, far_node), "<clip><far> (metres)")
    if near is not None and far is not None and far <= near:
        raise SourceError(f"<clip><far> {far:g} m must exceed <near> {near:g} m", path=doc.path,
                          field=_where(doc, far_node if far_node is not None else camera))
    rate_node = sensor.find("update_rate")
    rate = _positive(doc, rate_node, read_float(doc, rate_node), "<update_rate> (Hz; 0 means unthrottled)",
                     zero_ok=True)
    return CameraSpec(
        name=name, sensor_name=sensor_name, camera_name=camera_name, sensor_type=sensor.get("type", ""),
        link=link, T_link_camera=parse_pose(doc, sensor.find("pose")) @ parse_pose(doc, camera.find("pose")),
        width=_image_size(doc, camera, "width"), height=_image_size(doc, camera, "height"), hfov_rad=hfov,
        clip_near_m=near, clip_far_m=far, update_rate_hz=rate,
        distortion=_distortion(doc, camera), noise=_noise(doc, camera), lens=_lens(doc, camera),
        plugin=_plugin(doc, sensor), T_link_sensor=parse_pose(doc, sensor.find("pose")),
        index_in_sensor=index, cameras_in_sensor=count,
        lines={"sensor": doc.line(sensor), "camera": doc.line(camera), "horizontal_fov": doc.line(hfov_node),
               "pose": doc.line(camera.find("pose")) or doc.line(sensor.find("pose")),
               "clip": doc.line(clip), "update_rate": doc.line(sensor.find("update_rate"))},
    )


def camera_specs(doc: XmlDoc, sensor: ET.Element, link: str) -> list[CameraSpec]:
    """Every camera of a camera-like ``<sensor>`` attached to ``link`` (empty for other sensor types)."""
    if sensor.get("type", "") not in CAMERA_SENSOR_TYPES:
        return []
    cameras = sensor.findall("camera")
    return [_one_camera(doc, sensor, cam, link, i, len(cameras)) for i, cam in enumerate(cameras)]
