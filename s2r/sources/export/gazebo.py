"""Gazebo sensor XML that makes a simulated stereo camera match a profile (``s2r profile export-gazebo``).

Formats:

- ``urdf``: two links joined by a fixed joint (the profile's baseline and rotation) with ``<gazebo>`` camera
  sensors and gazebo_ros camera plugins (``hackBaseline`` on the right one) - Gazebo classic.
- ``sdf``: one ``multicamera`` sensor with cameras ``left`` and ``right`` (the right one's ``<pose>``) and
  libgazebo_ros_multicamera.so with ``hackBaseline`` - Gazebo classic.
- ``gz-sim``: two ``camera`` sensors - new Gazebo.

Every camera carries ``<lens><intrinsics>`` (fx, fy, cx, cy, s; both simulators render with it) and
``horizontal_fov = 2 atan(W / (2 fx))``, the exact inverse of every convention's focal length. Distortion is
converted to Gazebo's image-normalised model (:mod:`s2r.sources.conventions`) about the profile's principal point
(``<distortion><center>``), written in Gazebo classic's default units and, for gz-sim, in gz-rendering's scaled
ones. The gazebo_ros plugins get ``borderCrop`` false (their default crop magnifies a barrel-distorted image) and
camera_info K and D from the profile. What a format cannot express, and what gz-sim does that no SDF element
controls (no distortion under ogre2, the crop), comes back as warnings that state the error left, in pixels.

Pasting into a ROS robot: the URDF snippet defines the ``*_optical_frame`` links its plugins publish (joint
rpy -pi/2 0 -pi/2 from each camera link) and, given ``parent_link``, the joint that mounts the rig on it.
Image noise is emitted only from a sensor noise figure (``noise``, else the fitted sensor model's
``sensor.image_noise_dn / 255``, else ``simulation.noise_stddev``), never from a calibration's reprojection
error (that is corner localisation, not sensor noise). A RealSense's
infrared imagers are mono (``L8``) and publish on realsense2_camera's topics (``camera/infra1/image_rect_raw``).
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from s2r.errors import SourceError
from s2r.geometry import T_LINK_OPTICAL, invert_transform, pose_from_opencv_extrinsics, rpy_from_rotation
from s2r.profile import Camera, StereoProfile
from s2r.sources.conventions import (
    CENTRE_OFFSET_PX,
    LENS_OFFSET_PX,
    crop_magnification,
    gz_sim_distortion_scale,
    hfov_from_focal,
    opencv_to_gazebo_distortion,
    scale_distortion,
    texture_center,
)
from s2r.sources.description import FloatArray
from s2r.sources.xmlparse import parse_xml

__all__ = ["EXPORT_FORMATS", "FY_WARN_EDGE_PX", "OPTICAL_RPY", "comment_text", "export_gazebo", "is_realsense",
           "lens_intrinsics"]

EXPORT_FORMATS = ("urdf", "sdf", "gz-sim")
#: warn about camera_info's fy = fx only past this shift at the image's top and bottom edges, pixels.
FY_WARN_EDGE_PX = 0.1
#: rpy of a ROS optical frame in its camera link (z forward, x right, y down).
OPTICAL_RPY = f"{-math.pi / 2!r} 0 {-math.pi / 2!r}"


#: Characters XML 1.0 cannot carry at all, escaped or not (C0 controls but tab/LF/CR, surrogates, U+FFFE/FFFF).
_NOT_XML = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def comment_text(text: str) -> str:
    """``text`` made safe inside ``<!-- -->``: no ``--`` (``cam--v2`` -> ``cam- -v2``), no trailing ``-``, no
    character XML cannot carry (shown as ``?``)."""
    safe = _NOT_XML.sub("?", text)
    while "--" in safe:
        safe = safe.replace("--", "- -")
    return safe + " " if safe.endswith("-") else safe


def _xml_value(value: str, field: str) -> str:
    """``value`` for an XML attribute or text (ElementTree escapes ``< & > "``); SourceError when it holds a
    character no XML file can carry (a control character)."""
    bad = _NOT_XML.search(value)
    if bad:
        raise SourceError(f"{value[:60]!a} holds the character {bad.group()!a}, which no XML file can carry",
                          field=field, hint="use letters, digits, '_', '-' and '.'")
    return value


def _num(value: float) -> str:
    """Shortest text that reads back as the same float (exact round trip), ``0`` for tiny values."""
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    rounded = round(float(value), 15)
    return "0" if rounded == 0 else repr(rounded)


def _sub(parent: ET.Element, tag: str, text: str | float | int | None = None, **attrs: str) -> ET.Element:
    node = ET.SubElement(parent, tag, attrs)
    if text is not None:
        node.text = text if isinstance(text, str) else _num(text)
    return node


def lens_intrinsics(profile: StereoProfile, cam: Camera) -> tuple[float, float, float, float, float]:
    """``(fx, fy, cx, cy, s)`` of ``cam`` (one of ``profile``'s cameras) as ``<lens><intrinsics>`` takes them.

    Both Gazebo classic and gz-sim render with these; cx, cy are in continuous pixel coordinates (OpenCV's
    0-based principal point + 0.5), converted from the profile's own pixel convention. The one place that
    decides what a user types into ``<lens><intrinsics>`` (export and validate's advice both use it).
    """
    shift = LENS_OFFSET_PX - CENTRE_OFFSET_PX.get(profile.provenance.convention, 0.0)
    return cam.fx_px, cam.fy_px, cam.cx_px + shift, cam.cy_px + shift, cam.skew


def is_realsense(profile: StereoProfile) -> bool:
    """True for a RealSense infrared pair (imported from rs-enumerate-devices, or its infra optical frames)."""
    return "infra1" in profile.left.frame_id or "rs-enumerate-devices" in profile.provenance.method \
        or profile.name.lower().startswith("realsense")


class _Exporter:
    def __init__(self, profile: StereoProfile, fmt: str, noise: float | None) -> None:
        self.profile, self.fmt = profile, fmt
        self.warnings: list[str] = []
        self.offset = CENTRE_OFFSET_PX.get(profile.provenance.convention, 0.0)
        sim = profile.simulation
        fitted = profile.sensor.image_noise_dn if profile.sensor is not None else None  # grey levels, 0..255
        self.noise = (noise if noise is not None else fitted / 255.0 if fitted is not None
                      else sim.noise_stddev if sim is not None else None)
        self.realsense = is_realsense(profile)

    def topic(self, side: str) -> tuple[str, str, str]:
        """(camera name, image topic, frame) as the real driver publishes them (realsense2_camera for a RealSense)."""
        if self.realsense:
            n = 1 if side == "left" else 2
            return f"camera/infra{n}", "image_rect_raw", f"camera_infra{n}_optical_frame"
        p = self.profile
        return f"{p.name}/{side}", "image_raw", f"{p.name}_{side}_optical_frame"

    def check_camera(self, side: str, cam: Camera) -> None:
        # camera_info's fy = fx moves a point at the top or bottom edge by this much: warn only when it shows
        edge_px = abs(cam.fx_px - cam.fy_px) / cam.fy_px * (cam.height_px / 2.0)
        if self.fmt != "gz-sim" and edge_px > FY_WARN_EDGE_PX:
            self.warnings.append(f"{side}: fx {cam.fx_px:.3f} != fy {cam.fy_px:.3f}: the image renders with both "
                                 "(<lens><intrinsics>) but gazebo_ros' camera_info publishes fx for both, "
                                 f"{edge_px:.2f} px off at the top and bottom edges")

    def camera(self, parent: ET.Element, side: str, cam: Camera, *, name: str | None = None) -> ET.Element:
        self.check_camera(side, cam)
        node = _sub(parent, "camera", **({"name": name} if name else {}))
        _sub(node, "horizontal_fov", hfov_from_focal(cam.width_px, cam.fx_px))
        image = _sub(node, "image")
        _sub(image, "width", cam.width_px)
        _sub(image, "height", cam.height_px)
        _sub(image, "format", "L8" if self.realsense else "R8G8B8")
        sim = self.profile.simulation
        clip = _sub(node, "clip")
        _sub(clip, "near", sim.clip_near_m if sim else 0.05)
        _sub(clip, "far", sim.clip_far_m if sim else 100.0)
        if self.noise is not None:
            noise = _sub(node, "noise")
            _sub(noise, "type", "gaussian")
            _sub(noise, "mean", 0.0)
            _sub(noise, "stddev", self.noise)
        self.distortion(node, side, cam)
        intr = _sub(_sub(node, "lens"), "intrinsics")
        for tag, value in zip(("fx", "fy", "cx", "cy", "s"), lens_intrinsics(self.profile, cam), strict=True):
            _sub(intr, tag, value)
        return node

    def distortion(self, node: ET.Element, side: str, cam: Camera) -> None:
        if cam.distortion.is_zero:
            return
        if cam.distortion.model != "plumb_bob":
            self.warnings.append(f"{side}: {cam.distortion.model} distortion has no Gazebo equivalent and was dropped")
            return
        # Distortion about the principal point the simulator renders (exact 0-based pixels; <lens><intrinsics>)
        principal = (cam.cx_px - self.offset, cam.cy_px - self.offset)
        fit = opencv_to_gazebo_distortion(cam.distortion.coefficients, width=cam.width_px, height=cam.height_px,
                                          fx=cam.fx_px, fy=cam.fy_px, principal=principal)
        if fit.max_px > 0.01:
            self.warnings.append(f"{side}: plumb_bob distortion converted to Gazebo's image-normalised model with "
                                 f"{fit.rms_px:.3f} px RMS, {fit.max_px:.3f} px worst error (non-square image)")
        coeffs = fit.coefficients
        center = texture_center(cam.width_px, cam.height_px, *principal)
        if self.fmt == "gz-sim":
            self.gz_sim_notes(side, cam, coeffs, center)
            coeffs = scale_distortion(coeffs, gz_sim_distortion_scale(cam.width_px, cam.height_px,
                                                                      hfov_from_focal(cam.width_px, cam.fx_px)))
        elif coeffs[0] >= 0:
            self.warnings.append(f"{side}: Gazebo classic only renders barrel distortion (k1 < 0); k1 = "
                                 f"{coeffs[0]:.6g} may be ignored by the simulator")
        dist = _sub(node, "distortion")
        for tag, value in zip(("k1", "k2", "k3", "p1", "p2"), coeffs, strict=True):
            _sub(dist, tag, value)
        _sub(dist, "center", f"{_num(center[0])} {_num(center[1])}")


    def gz_sim_notes(self, side: str, cam: Camera, coeffs: tuple[float, ...], center: tuple[float, float]) -> None:
        """What gz-sim does to a lens that no SDF element controls (gz-rendering / gz-sensors source)."""
        self.warnings.append(f"{side}: gz-sim renders <distortion> only with the ogre render engine (ogre2, the "
                             "default, has no distortion pass): run the world with --render-engine ogre")
        mx, my = crop_magnification((coeffs[0], coeffs[1], coeffs[2], coeffs[3], coeffs[4]), center)
        if max(mx, my) > 1.0005:
            self.warnings.append(f"{side}: gz-sim crops a barrel-distorted image (k1 < 0) to hide its black border, "
                                 f"magnifying it {mx:.4f} x {my:.4f}: it renders fx {cam.fx_px * mx:.2f}, not "
                                 f"{cam.fx_px:.2f} (no SDF switch; Gazebo classic's is borderCrop, set false here)")


def _pose_text(T: FloatArray) -> str:
    return " ".join(_num(v) for v in [*T[:3, 3], *rpy_from_rotation(T[:3, :3])])


def _optical_pose(profile: StereoProfile) -> FloatArray:
    """Pose of the right camera's Gazebo camera frame (+x forward) in the left one's."""
    T_opt = pose_from_opencv_extrinsics(profile.R, profile.T)
    return T_LINK_OPTICAL @ T_opt @ invert_transform(T_LINK_OPTICAL)


def _plugin(parent: ET.Element, filename: str, name: str, frame: str, hack: float | None, image_topic: str,
            cam: Camera | None = None, offset: float = 0.0) -> None:
    """gazebo_ros camera plugin; ``cam`` (one camera per plugin) also sets its camera_info K and D (OpenCV's
    0-based pixels). ``borderCrop`` false: the crop would magnify a barrel-distorted image."""
    plugin = _sub(parent, "plugin", name=f"{name.replace('/', '_')}_controller", filename=filename)
    _sub(plugin, "borderCrop", "false")
    if cam is not None:
        _sub(plugin, "focalLength", cam.fx_px)
        _sub(plugin, "Cx", cam.cx_px - offset)
        _sub(plugin, "Cy", cam.cy_px - offset)
        if cam.distortion.model == "plumb_bob":
            k1, k2, p1, p2, k3 = (tuple(cam.distortion.coefficients) + (0.0,) * 5)[:5]
            for tag, value in (("K1", k1), ("K2", k2), ("K3", k3), ("T1", p1), ("T2", p2)):
                _sub(plugin, f"distortion{tag}", value)
    _sub(plugin, "alwaysOn", "true")
    _sub(plugin, "updateRate", 0.0)
    _sub(plugin, "cameraName", name)
    _sub(plugin, "imageTopicName", image_topic)
    _sub(plugin, "cameraInfoTopicName", "camera_info")
    _sub(plugin, "frameName", frame)
    if hack is not None:
        _sub(plugin, "hackBaseline", hack)


def _sensor(parent: ET.Element, kind: str, name: str, rate: float) -> ET.Element:
    sensor = _sub(parent, "sensor", type=kind, name=name)
    _sub(sensor, "update_rate", rate)
    return sensor


def _urdf(ex: _Exporter, parent_link: str | None) -> ET.Element:
    p = ex.profile
    robot = ET.Element("robot", name=p.name)
    rate = p.simulation.update_rate_hz if p.simulation and p.simulation.update_rate_hz else 30.0
    frames = {side: ex.topic(side)[2] for side in ("left", "right")}
    for side in ("left", "right"):
        _sub(robot, "link", name=f"{p.name}_{side}_link")
        _sub(robot, "link", name=frames[side])
    if parent_link:
        mount = _sub(robot, "joint", name=f"{p.name}_mount_joint", type="fixed")
        _sub(mount, "parent", link=parent_link)
        _sub(mount, "child", link=f"{p.name}_left_link")
        _sub(mount, "origin", xyz="0 0 0", rpy="0 0 0")
    joint = _sub(robot, "joint", name=f"{p.name}_left_to_right", type="fixed")
    _sub(joint, "parent", link=f"{p.name}_left_link")
    _sub(joint, "child", link=f"{p.name}_right_link")
    T = _optical_pose(p)
    _sub(joint, "origin", xyz=" ".join(_num(v) for v in T[:3, 3]),
         rpy=" ".join(_num(v) for v in rpy_from_rotation(T[:3, :3])))
    for side in ("left", "right"):
        optical = _sub(robot, "joint", name=f"{frames[side]}_joint", type="fixed")
        _sub(optical, "parent", link=f"{p.name}_{side}_link")
        _sub(optical, "child", link=frames[side])
        _sub(optical, "origin", xyz="0 0 0", rpy=OPTICAL_RPY)
    for side, cam in (("left", p.left), ("right", p.right)):
        gazebo = _sub(robot, "gazebo", reference=f"{p.name}_{side}_link")
        sensor = _sensor(gazebo, "camera", f"{side}_camera", rate)
        ex.camera(sensor, side, cam, name=side)
        name, topic, frame = ex.topic(side)
        _plugin(sensor, "libgazebo_ros_camera.so", name, frame, p.baseline_m if side == "right" else None, topic,
                cam, ex.offset)
    return robot


def _sdf(ex: _Exporter) -> ET.Element:
    p = ex.profile
    gz = ex.fmt == "gz-sim"
    sdf = ET.Element("sdf", version="1.9" if gz else "1.6")
    model = _sub(sdf, "model", name=p.name)
    _sub(model, "static", "true")
    link = _sub(model, "link", name="stereo_camera_link")
    rate = p.simulation.update_rate_hz if p.simulation and p.simulation.update_rate_hz else 30.0
    T_right = _optical_pose(p)
    if gz:
        for side, cam, pose in (("left", p.left, np.eye(4)), ("right", p.right, T_right)):
            sensor = _sensor(link, "camera", f"{side}_camera", rate)
            _sub(sensor, "pose", _pose_text(pose))
            name, topic, frame = ex.topic(side)
            _sub(sensor, "topic", f"{name}/{topic}")
            node = ex.camera(sensor, side, cam, name=side)
            _sub(node, "optical_frame_id", frame)
        return sdf
    sensor = _sensor(link, "multicamera", "stereo_camera", rate)
    ex.camera(sensor, "left", p.left, name="left")
    right = ex.camera(sensor, "right", p.right, name="right")
    right.insert(0, ET.Element("pose"))
    right[0].text = _pose_text(T_right)
    _plugin(sensor, "libgazebo_ros_multicamera.so", "camera" if ex.realsense else p.name, ex.topic("left")[2],
            p.baseline_m, ex.topic("left")[1])
    return sdf


def export_gazebo(profile: StereoProfile, *, fmt: str = "urdf", noise: float | None = None,
                  parent_link: str | None = None) -> tuple[str, list[str]]:
    """Gazebo XML (``urdf`` | ``sdf`` | ``gz-sim``) for ``profile`` and warnings about what it cannot express.

    Args:
        noise: Gaussian image noise stddev (intensities 0..1) of the sensor; default the profile's fitted
            ``sensor.image_noise_dn / 255``, else ``simulation.noise_stddev``; none is emitted without one.
        parent_link: URDF only: the robot link the rig (its left camera link) is mounted on with a fixed joint.

    Returns:
        (XML text, warnings). Warnings say what was lost and the error it leaves in pixels.
    """
    if fmt not in EXPORT_FORMATS:
        raise SourceError(f"unknown export format {fmt!r}", field="--format", hint=f"use {', '.join(EXPORT_FORMATS)}")
    if noise is not None and not (0.0 <= noise <= 1.0 and math.isfinite(noise)):
        raise SourceError(f"noise stddev must be in [0, 1] (intensities), got {noise}", field="--noise")
    _xml_value(profile.name, "name")
    if parent_link is not None:
        _xml_value(parent_link, "--parent-link")
    ex = _Exporter(profile, fmt, noise)
    root = _urdf(ex, parent_link) if fmt == "urdf" else _sdf(ex)
    ET.indent(root, space="  ")
    about = comment_text(f"s2r profile export-gazebo, format {fmt}: {profile.name} ({profile.provenance.origin}, "
                         f"{profile.provenance.convention} pixels); baseline {profile.baseline_m:.6g} m. "
                         "horizontal_fov = 2 atan(W / (2 fx)).")
    text = f"<?xml version=\"1.0\"?>\n<!-- {about} -->\n" + ET.tostring(root, encoding="unicode") + "\n"
    parse_xml(text, Path(f"export-gazebo {fmt}"))  # s2r's own reader accepts every export (else a bug here)
    return text, ex.warnings
