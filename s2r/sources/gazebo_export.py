"""Gazebo sensor XML that makes a simulated stereo camera match a profile (``s2r profile export-gazebo``).

Formats:

- ``urdf``: two links joined by a fixed joint (the profile's baseline and rotation) with ``<gazebo>`` camera
  sensors and gazebo_ros camera plugins (``hackBaseline`` on the right one) - Gazebo classic.
- ``sdf``: one ``multicamera`` sensor with cameras ``left`` and ``right`` (the right one's ``<pose>``) and
  libgazebo_ros_multicamera.so with ``hackBaseline`` - Gazebo classic.
- ``gz-sim``: two ``camera`` sensors with ``<lens><intrinsics>`` (fx, fy, cx, cy, s) - new Gazebo.

``horizontal_fov = 2 atan(W / (2 fx))`` is the exact inverse of every convention's focal length. Distortion
is converted to Gazebo's image-normalised units (:mod:`s2r.sources.conventions`). What a format cannot
express comes back as warnings that state the error left, in pixels.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np

from s2r.errors import SourceError
from s2r.geometry import T_LINK_OPTICAL, invert_transform, pose_from_opencv_extrinsics, rpy_from_rotation
from s2r.profile import Camera, StereoProfile
from s2r.sources.conventions import CENTRE_OFFSET_PX, hfov_from_focal, opencv_to_gazebo_distortion
from s2r.sources.description import FloatArray

__all__ = ["EXPORT_FORMATS", "export_gazebo", "noise_from_residual"]

EXPORT_FORMATS = ("urdf", "sdf", "gz-sim")
#: Edge-localisation model used to turn a calibration RMS (pixels) into intensity noise (0..1):
#: sigma_px = sigma_I * w / (C * sqrt(N)) with edge blur w, contrast C and N pixels across the edges.
NOISE_MODEL = {"edge_blur_px": 1.5, "contrast": 1.0, "pixels": 66}
NOISE_MAX = 0.05


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


def noise_from_residual(rms_px: float) -> tuple[float, bool]:
    """Gaussian intensity noise (0..1) whose corner-localisation error equals ``rms_px`` under
    :data:`NOISE_MODEL`, capped at :data:`NOISE_MAX`; returns (stddev, capped)."""
    m = NOISE_MODEL
    sigma = rms_px * m["contrast"] * math.sqrt(m["pixels"]) / m["edge_blur_px"]
    return min(sigma, NOISE_MAX), sigma > NOISE_MAX


class _Exporter:
    def __init__(self, profile: StereoProfile, fmt: str) -> None:
        self.profile, self.fmt = profile, fmt
        self.warnings: list[str] = []
        self.offset = CENTRE_OFFSET_PX.get(profile.provenance.convention, 0.0)
        self.noise = self._noise()

    def _noise(self) -> float | None:
        sim, cal = self.profile.simulation, self.profile.provenance.calibration
        if sim is not None and sim.noise_stddev is not None:
            return sim.noise_stddev
        rms = None if cal is None else next((r for r in (cal.rms_stereo_px, cal.rms_left_px) if r is not None), None)
        if rms is None:
            return None
        sigma, capped = noise_from_residual(rms)
        self.warnings.append(f"image noise stddev {sigma:.4f} from the calibration RMS {rms:.3f} px (edge model "
                             f"{NOISE_MODEL})" + (f", capped at {NOISE_MAX}: most of that residual is not sensor "
                                                  "noise" if capped else ""))
        return sigma

    def check_camera(self, side: str, cam: Camera) -> None:
        w, h = cam.width_px, cam.height_px
        if self.fmt != "gz-sim":
            if abs(cam.fx_px - cam.fy_px) > 1e-9 * cam.fx_px:
                err = (h / 2.0) * abs(cam.fx_px / cam.fy_px - 1.0)
                self.warnings.append(f"{side}: fx {cam.fx_px:.3f} != fy {cam.fy_px:.3f} cannot be expressed in Gazebo "
                                     f"classic (fy = fx is used): {err:.2f} px error at the top and bottom edges")
            dx = cam.cx_px - self.offset - (w - 1) / 2.0
            dy = cam.cy_px - self.offset - (h - 1) / 2.0
            if math.hypot(dx, dy) > 0.01:
                self.warnings.append(f"{side}: off-centre principal point ({cam.cx_px:.2f}, {cam.cy_px:.2f}) cannot be "
                                     f"expressed in Gazebo classic (it renders centred): {math.hypot(dx, dy):.2f} px "
                                     f"error ({dx:+.2f}, {dy:+.2f})")
            if cam.skew:
                self.warnings.append(f"{side}: skew {cam.skew:g} dropped: up to {abs(cam.skew) * h / 2 / cam.fy_px:.2f}"
                                     " px error at the image edges")

    def camera(self, parent: ET.Element, side: str, cam: Camera, *, name: str | None = None) -> ET.Element:
        self.check_camera(side, cam)
        node = _sub(parent, "camera", **({"name": name} if name else {}))
        _sub(node, "horizontal_fov", hfov_from_focal(cam.width_px, cam.fx_px))
        image = _sub(node, "image")
        _sub(image, "width", cam.width_px)
        _sub(image, "height", cam.height_px)
        _sub(image, "format", "R8G8B8")
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
        if self.fmt == "gz-sim":
            intr = _sub(_sub(node, "lens"), "intrinsics")
            shift = CENTRE_OFFSET_PX["gz-sim"] - self.offset
            for tag, value in (("fx", cam.fx_px), ("fy", cam.fy_px), ("cx", cam.cx_px + shift),
                               ("cy", cam.cy_px + shift), ("s", cam.skew)):
                _sub(intr, tag, value)
        return node

    def distortion(self, node: ET.Element, side: str, cam: Camera) -> None:
        if cam.distortion.is_zero:
            return
        if cam.distortion.model != "plumb_bob":
            self.warnings.append(f"{side}: {cam.distortion.model} distortion has no Gazebo equivalent and was dropped")
            return
        fit = opencv_to_gazebo_distortion(cam.distortion.coefficients, width=cam.width_px, height=cam.height_px,
                                          fx=cam.fx_px, fy=cam.fy_px)
        if fit.max_px > 0.01:
            self.warnings.append(f"{side}: plumb_bob distortion converted to Gazebo's image-normalised model with "
                                 f"{fit.rms_px:.3f} px RMS, {fit.max_px:.3f} px worst error (non-square image)")
        if fit.coefficients[0] >= 0:
            self.warnings.append(f"{side}: Gazebo classic only renders barrel distortion (k1 < 0); k1 = "
                                 f"{fit.coefficients[0]:.6g} may be ignored by the simulator")
        dist = _sub(node, "distortion")
        for tag, value in zip(("k1", "k2", "k3", "p1", "p2"), fit.coefficients, strict=True):
            _sub(dist, tag, value)
        _sub(dist, "center", "0.5 0.5")


def _pose_text(T: FloatArray) -> str:
    return " ".join(_num(v) for v in [*T[:3, 3], *rpy_from_rotation(T[:3, :3])])


def _optical_pose(profile: StereoProfile) -> FloatArray:
    """Pose of the right camera's Gazebo camera frame (+x forward) in the left one's."""
    T_opt = pose_from_opencv_extrinsics(profile.R, profile.T)
    return T_LINK_OPTICAL @ T_opt @ invert_transform(T_LINK_OPTICAL)


def _plugin(parent: ET.Element, filename: str, name: str, frame: str, hack: float | None) -> None:
    plugin = _sub(parent, "plugin", name=f"{name}_controller", filename=filename)
    _sub(plugin, "alwaysOn", "true")
    _sub(plugin, "updateRate", 0.0)
    _sub(plugin, "cameraName", name)
    _sub(plugin, "imageTopicName", "image_raw")
    _sub(plugin, "cameraInfoTopicName", "camera_info")
    _sub(plugin, "frameName", frame)
    if hack is not None:
        _sub(plugin, "hackBaseline", hack)


def _sensor(parent: ET.Element, kind: str, name: str, rate: float) -> ET.Element:
    sensor = _sub(parent, "sensor", type=kind, name=name)
    _sub(sensor, "update_rate", rate)
    return sensor


def _urdf(ex: _Exporter) -> ET.Element:
    p = ex.profile
    robot = ET.Element("robot", name=p.name)
    rate = p.simulation.update_rate_hz if p.simulation and p.simulation.update_rate_hz else 30.0
    for side in ("left", "right"):
        _sub(robot, "link", name=f"{p.name}_{side}_link")
    joint = _sub(robot, "joint", name=f"{p.name}_left_to_right", type="fixed")
    _sub(joint, "parent", link=f"{p.name}_left_link")
    _sub(joint, "child", link=f"{p.name}_right_link")
    T = _optical_pose(p)
    _sub(joint, "origin", xyz=" ".join(_num(v) for v in T[:3, 3]),
         rpy=" ".join(_num(v) for v in rpy_from_rotation(T[:3, :3])))
    for side, cam in (("left", p.left), ("right", p.right)):
        gazebo = _sub(robot, "gazebo", reference=f"{p.name}_{side}_link")
        sensor = _sensor(gazebo, "camera", f"{side}_camera", rate)
        ex.camera(sensor, side, cam, name=side)
        _plugin(sensor, "libgazebo_ros_camera.so", f"{p.name}/{side}", f"{p.name}_{side}_optical_frame",
                p.baseline_m if side == "right" else None)
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
            _sub(sensor, "topic", f"{p.name}/{side}/image_raw")
            node = ex.camera(sensor, side, cam, name=side)
            _sub(node, "optical_frame_id", f"{p.name}_{side}_optical_frame")
        return sdf
    sensor = _sensor(link, "multicamera", "stereo_camera", rate)
    ex.camera(sensor, "left", p.left, name="left")
    right = ex.camera(sensor, "right", p.right, name="right")
    right.insert(0, ET.Element("pose"))
    right[0].text = _pose_text(T_right)
    _plugin(sensor, "libgazebo_ros_multicamera.so", p.name, f"{p.name}_left_optical_frame", p.baseline_m)
    return sdf


def export_gazebo(profile: StereoProfile, *, fmt: str = "urdf") -> tuple[str, list[str]]:
    """Gazebo XML (``urdf`` | ``sdf`` | ``gz-sim``) for ``profile`` and warnings about what it cannot express.

    Returns:
        (XML text, warnings). Warnings say what was lost and the error it leaves in pixels.
    """
    if fmt not in EXPORT_FORMATS:
        raise SourceError(f"unknown export format {fmt!r}", field="--format", hint=f"use {', '.join(EXPORT_FORMATS)}")
    ex = _Exporter(profile, fmt)
    root = _urdf(ex) if fmt == "urdf" else _sdf(ex)
    ET.indent(root, space="  ")
    header = (f"<?xml version=\"1.0\"?>\n<!-- s2r profile export-gazebo, format {fmt}: {profile.name} "
              f"({profile.provenance.origin}, {profile.provenance.convention} pixels); baseline "
              f"{profile.baseline_m:.6g} m. horizontal_fov = 2 atan(W / (2 fx)). -->\n")
    return header + ET.tostring(root, encoding="unicode") + "\n", ex.warnings
