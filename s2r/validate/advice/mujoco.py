"""What to change in a MuJoCo sim: the ``<camera>`` attributes of an MJCF model that make it match the real camera.

A sim profile read from an MJCF (``s2r profile from-description model.xml``) gets these edits instead of
Gazebo's: ``resolution="W H"``, ``fovy`` (the VERTICAL field of view in degrees: ``fy = (H / 2) / tan(fovy / 2)``)
when the real camera is square-pixelled and centred, else ``sensorsize`` + ``focalpixel`` + ``principalpixel``
(``px = (W - 1) / 2 - cx``, ``py = (H - 1) / 2 - cy``, OpenCV 0-based pixels), and the right camera's ``pos``
moved by the difference of the two profiles' right-camera positions in the left camera's MuJoCo frame (x right,
y up, z backward: the OpenCV optical frame with y and z negated). Every value is the one
``s2r profile export-mujoco REAL`` writes, whose command ends the list (its camera pair is a drop-in
``<include>``). MJCF has no lens model: a distortion difference is named with the remap that applies it.
"""

from __future__ import annotations

import math

import numpy as np

from s2r.profile import Camera, StereoProfile
from s2r.sources.export.mujoco import PIXEL_PITCH_M, distortion_residual_px
from s2r.validate.advice.edits import Edit, _failed, _fmt
from s2r.validate.measures.params import ParamRow

__all__ = ["is_mujoco_sim", "mujoco_fovy_deg", "suggest_mujoco_edits"]

#: MJCF <camera> attributes are written in both cameras unless named otherwise.
_BOTH = "on both <camera> elements of the MJCF"


def is_mujoco_sim(profile: StereoProfile) -> bool:
    """Whether the profile was read from an MJCF model (``s2r profile from-description`` on a ``<mujoco>`` file)."""
    return profile.provenance.method.rstrip().endswith("(mjcf)")


def mujoco_fovy_deg(cam: Camera) -> float:
    """MuJoCo's ``fovy`` (degrees, vertical) that renders the camera's ``fy`` at its height."""
    return math.degrees(2.0 * math.atan(cam.height_px / (2.0 * cam.fy_px)))


def _centred(cam: Camera, tol_px: float) -> bool:
    return (abs(cam.cx_px - (cam.width_px - 1) / 2.0) <= tol_px and abs(cam.cy_px - (cam.height_px - 1) / 2.0)
            <= tol_px and abs(cam.fx_px - cam.fy_px) <= 1e-6 * cam.fx_px)


def _intrinsics(cam: Camera) -> str:
    w, h = cam.width_px, cam.height_px
    return (f'sensorsize="{_fmt((w * PIXEL_PITCH_M, h * PIXEL_PITCH_M))}" focalpixel="{cam.fx_px:.6g} '
            f'{cam.fy_px:.6g}" principalpixel="{(w - 1) / 2.0 - cam.cx_px:.6g} {(h - 1) / 2.0 - cam.cy_px:.6g}"')


def _pair_values(profile: StereoProfile) -> str:
    """``focalpixel "fx fy" principalpixel "px py"`` of the pair (once when both cameras agree)."""
    def one(cam: Camera) -> str:
        w, h = cam.width_px, cam.height_px
        return (f'focalpixel="{cam.fx_px:.6g} {cam.fy_px:.6g}" principalpixel="{(w - 1) / 2.0 - cam.cx_px:.4g} '
                f'{(h - 1) / 2.0 - cam.cy_px:.4g}"')

    left, right = one(profile.left), one(profile.right)
    return f"{left} (both)" if left == right else f"left {left}, right {right}"


def _right_pos_mj(profile: StereoProfile) -> tuple[float, ...]:
    """The right camera's centre in the left camera's MuJoCo frame (x right, y up, z backward), metres, rounded
    to the micrometre."""
    centre = -profile.R.T @ profile.T  # OpenCV optical frame of the left camera
    return tuple(float(v) + 0.0 for v in np.round(np.asarray(centre) * np.array([1.0, -1.0, -1.0]), 6))


def _lens_edits(sim: StereoProfile, real: StereoProfile, rows: list[ParamRow], *, pp_tol_px: float) -> list[Edit]:
    edits = []
    if _failed(rows, "image size"):
        edits.append(Edit("resolution", f"{sim.image_size[0]} {sim.image_size[1]}",
                          f"{real.image_size[0]} {real.image_size[1]}",
                          f'resolution="{real.image_size[0]} {real.image_size[1]}" {_BOTH} (and <visual><global '
                          f'offwidth="{real.image_size[0]}" offheight="{real.image_size[1]}"/> at least that large)'))
    pp_off = _failed(rows, "left cx", "left cy", "right cx", "right cy")
    if _failed(rows, "HFOV", "VFOV", "left fx", "right fx", "left fy", "right fy", "image size") or pp_off:
        if all(_centred(c, pp_tol_px) for c in (real.left, real.right)):
            edits.append(Edit("fovy", f"{mujoco_fovy_deg(sim.left):.4f} deg", f"{mujoco_fovy_deg(real.left):.4f} deg",
                              f'fovy="{mujoco_fovy_deg(real.left):.6g}" {_BOTH} (MuJoCo\'s fovy is the VERTICAL '
                              "field of view in degrees)"))
        else:
            edits.append(Edit("intrinsics", _pair_values(sim), _pair_values(real),
                              f"left <camera>: {_intrinsics(real.left)}; right <camera>: {_intrinsics(real.right)} "
                              "(with sensorsize MuJoCo ignores fovy)"))
    if _failed(rows, "left distortion", "right distortion"):
        worst = max(distortion_residual_px(real.left)[0], distortion_residual_px(real.right)[0])
        edits.append(Edit("distortion", sim.left.distortion.model, real.left.distortion.model,
                          f"MJCF has no lens model ({worst:.2f} px at worst): render through s2r with --renderer "
                          "mujoco, which remaps every frame through the real lens, or undistort the real images"))
    return edits


def suggest_mujoco_edits(sim: StereoProfile, real: StereoProfile, rows: list[ParamRow], *,
                         principal_point_px: float = 2.0) -> list[Edit]:
    """The edits to the MJCF that remove each parameter difference beyond tolerance, then the export command."""
    edits = _lens_edits(sim, real, rows, pp_tol_px=principal_point_px)
    if _failed(rows, "baseline", "inter-camera rotation"):
        now, want = _right_pos_mj(sim), _right_pos_mj(real)
        move = tuple(float(v) + 0.0 for v in np.round(np.subtract(want, now), 6))
        edits.append(Edit("right camera pos", f"({_fmt(now)}) m from the left camera",
                          f"({_fmt(want)}) m from the left camera",
                          f"move the right <camera> pos by ({_fmt(move)}) m along the left camera's own axes (x right, "
                          "y up, z backward: turn by its xyaxes/quat into its body's frame; baseline "
                          f"{sim.baseline_m * 1000:.1f} -> {real.baseline_m * 1000:.1f} mm); a rotation between the "
                          "cameras: take the export's quat"))
    if edits:
        edits.append(Edit("MJCF cameras", sim.name, real.name,
                          f"s2r profile export-mujoco {real.name} -o {real.name}_cameras.xml (a drop-in camera pair: "
                          "<include file=\"...\"/> it in place of the two cameras)"))
    return edits
