"""MJCF that makes a MuJoCo camera pair render like a profile (``s2r profile export-mujoco``).

The file is a complete ``<mujoco>`` model (loadable by ``mujoco.MjModel.from_xml_path``) and can be pulled into a
user's scene with ``<include file="cameras.xml"/>`` (or attached with ``MjSpec.attach``). It holds one body whose
frame is a robot's camera link (x forward, y left, z up) with the LEFT camera at its origin, and two cameras:

- ``resolution="W H"``, ``sensorsize`` (a nominal 3 um pixel pitch; only ratios matter), ``focalpixel="fx fy"``
  and ``principalpixel="px py"`` with ``px = (W - 1) / 2 - cx`` and ``py = (H - 1) / 2 - cy`` (cx, cy in OpenCV's
  0-based pixel-centre convention; MuJoCo renders the optical axis at ``(W - 1) / 2 - px``: both offsets enter
  with a minus sign, measured by rendering, see :mod:`s2r.render.mujoco.backend`);
- poses: a MuJoCo camera looks along its -z with +y up, i.e. ``R_body_cam = R_body_optical @ diag(1, -1, -1)``;
  the right camera's optical frame is ``T_left_right = [R | T]^-1`` from the profile's ``X_right = R X_left + T``.

MJCF has no lens distortion and no skew: what they move is reported as a residual in pixels (worst and 95th
percentile over the image: how far the real lens puts a point from where the exported pinhole does). Applying
the lens takes a remap of every rendered frame (for each output pixel, its undistorted ray, sampled in the
pinhole render), which ``s2r render ... --renderer mujoco`` does.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
from scipy.spatial.transform import Rotation

from s2r.errors import SourceError
from s2r.lens.distortion import distort_normalised
from s2r.names import NAME_HINT, is_safe_name
from s2r.profile import Camera, StereoProfile
from s2r.sources.description import FloatArray

__all__ = ["R_BODY_OPTICAL", "distortion_residual_px", "export_mujoco"]

#: Optical frame (z forward, x right, y down) in a camera link / body frame (x forward, y left, z up).
R_BODY_OPTICAL = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
#: OpenCV optical frame -> MuJoCo camera frame (looks along -z, +y up): a rotation by pi about x.
_FLIP = np.diag([1.0, -1.0, -1.0])
#: Nominal pixel pitch of the written sensorsize, metres.
PIXEL_PITCH_M = 3e-6
#: Residuals below this many pixels are not worth a warning.
_NEGLIGIBLE_PX = 0.01


def _num(value: float) -> str:
    rounded = round(float(value), 15)
    return "0" if rounded == 0 else repr(rounded)


def _vec(values: FloatArray | list[float] | tuple[float, ...]) -> str:
    return " ".join(_num(v) for v in values)


def distortion_residual_px(cam: Camera, *, steps: int = 64) -> tuple[float, float]:
    """(worst, 95th percentile) pixel distance, over a ``steps`` x ``steps`` grid spanning the image, between
    where the camera's lens (and skew) images a ray and where the same camera without them does."""
    u, v = np.meshgrid(np.linspace(0.0, cam.width_px - 1.0, steps), np.linspace(0.0, cam.height_px - 1.0, steps))
    y = (v - cam.cy_px) / cam.fy_px
    x = (u - cam.cx_px) / cam.fx_px
    xd, yd = distort_normalised(cam, x, y)
    ud = cam.fx_px * xd + cam.skew * yd + cam.cx_px
    vd = cam.fy_px * yd + cam.cy_px
    err = np.hypot(ud - u, vd - v)
    return float(err.max()), float(np.percentile(err, 95))


def _camera(body: ET.Element, name: str, cam: Camera, T_body_optical: FloatArray) -> None:
    q = Rotation.from_matrix(T_body_optical[:3, :3] @ _FLIP).as_quat()  # x, y, z, w
    w, h = cam.width_px, cam.height_px
    ET.SubElement(body, "camera", {
        "name": name, "pos": _vec(T_body_optical[:3, 3]), "quat": _vec([q[3], q[0], q[1], q[2]]),
        "resolution": f"{w} {h}", "sensorsize": _vec([w * PIXEL_PITCH_M, h * PIXEL_PITCH_M]),
        "focalpixel": _vec([cam.fx_px, cam.fy_px]),
        "principalpixel": _vec([(w - 1) / 2.0 - cam.cx_px, (h - 1) / 2.0 - cam.cy_px]),
    })


def _lens_warnings(side: str, cam: Camera) -> list[str]:
    worst, p95 = distortion_residual_px(cam)
    if worst < _NEGLIGIBLE_PX:
        return []
    what = [] if cam.distortion.is_zero else [f"{cam.distortion.model} distortion"]
    what += [f"skew {cam.skew:g}"] if cam.skew else []
    return [f"{side}: MJCF has no lens model: {' and '.join(what)} dropped, the pinhole render is off by up to "
            f"{worst:.2f} px ({p95:.2f} px at the 95th percentile) from the real camera; applying it takes a remap "
            "of every frame (render through s2r with --renderer mujoco, or undistort the real images instead)"]


def export_mujoco(profile: StereoProfile, *, body: str = "s2r_stereo") -> tuple[str, list[str]]:
    """MJCF text of a body holding the profile's two cameras (see the module docstring) and warnings that name, in
    pixels, what MJCF cannot express.

    Raises:
        SourceError: ``body`` is not a usable MJCF name.
    """
    if not is_safe_name(body):
        raise SourceError(f"not a usable MJCF body name: {body!r}", field="--body",
                          hint=NAME_HINT)
    p = profile.in_opencv_pixels()
    T_body_left = np.eye(4)
    T_body_left[:3, :3] = R_BODY_OPTICAL
    T_right_left = np.eye(4)
    T_right_left[:3, :3], T_right_left[:3, 3] = p.R, p.T
    T_body_right = T_body_left @ np.linalg.inv(T_right_left)
    root = ET.Element("mujoco", {"model": f"{body}_cameras"})
    size = max(p.left.width_px, p.right.width_px), max(p.left.height_px, p.right.height_px)
    ET.SubElement(ET.SubElement(root, "visual"), "global", {"offwidth": str(size[0]), "offheight": str(size[1])})
    frame = ET.SubElement(ET.SubElement(root, "worldbody"), "body", {"name": body, "pos": "0 0 0"})
    _camera(frame, f"{body}_left", p.left, T_body_left)
    _camera(frame, f"{body}_right", p.right, T_body_right)
    ET.indent(root, space="  ")
    warnings = _lens_warnings("left", p.left) + _lens_warnings("right", p.right)
    rot_deg = math.degrees(float(np.linalg.norm(Rotation.from_matrix(p.R).as_rotvec())))
    header = (f"<?xml version=\"1.0\"?>\n<!-- s2r profile export-mujoco: {_comment(profile.name)} "
              f"({profile.provenance.origin}); baseline {p.baseline_m:.6g} m, stereo rotation {rot_deg:.4g} deg. "
              f"Body frame: x forward, y left, z up, left camera at its origin. cx = (W - 1) / 2 - principalpixel "
              f"x, cy = (H - 1) / 2 - principalpixel y (OpenCV pixels). No lens distortion (MJCF has none). -->\n")
    return header + ET.tostring(root, encoding="unicode") + "\n", warnings


def _comment(text: str) -> str:
    """``text`` safe inside an XML comment."""
    return text.replace("--", "- -")
