"""ROS camera_info: the camera_calibration_parsers YAML pair (left.yaml/right.yaml) and ``rostopic echo`` text.

A stereo profile exports as two camera_info files of the RECTIFIED pair (OpenCV ``stereoRectify`` through
:func:`s2r.rectification.stereo_rectification`): each holds the raw K and D, the rectifying rotation R
(R1 / R2) and the rectified projection P (P1 / P2). The right camera's ``P[0, 3]`` (Tx) is ``-fx' * B``,
the left one's 0.

Import (:mod:`s2r.formats.ros_read`) inverts this: with ``P = K' [I | t]`` for each camera, points in the rectified
frame satisfy ``R2 X_right = R1 X_left + (t2 - t1)``, so ``R = R2^T R1`` and ``T = R2^T (t2 - t1)`` (OpenCV
convention, ``X_right = R X_left + T``, metres as in P's Tx).

What ROS's own nodes need of the exported pair (Debian's ROS 1, image_pipeline 1.17, image_geometry 1.16):
- image_proc's rectify nodelet passes ``image_raw`` through untouched when every coefficient of D is exactly 0,
  and image_geometry's C++ PinholeCameraModel then treats the camera as undistorted (R and P ignored). A pair
  with zero distortion but a rectifying rotation (any real pair: a D435's factory calibration reports zero
  coefficients) would come out unrectified. Export then writes the last coefficient (k3, k6 or k4) as
  :data:`ZERO_DISTORTION_MARKER`: non-zero for those checks, yet ``1 + 1e-20 r^6`` is exactly 1 in double
  precision for every ray within 78 deg of the axis, so OpenCV's maps are bit-identical to zero distortion.
- stereo_image_proc asserts that the left and right camera_info share one frame_id: both carry the left
  camera's (the rectified pair's P is expressed in it).
- What camera_info cannot say (the pixel convention, the matcher settings with num_disparities and the depth
  range, the frame_id, the marker) goes in an ``s2r:`` mapping that camera_calibration_parsers ignores and
  s2r reads back, so s2r -> ROS -> s2r keeps them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from s2r.errors import FormatError
from s2r.fileio import OutputBatch, check_output_free, prepare_output_dir
from s2r.geometry import baseline_layout_problem
from s2r.profile import Camera, StereoProfile

__all__ = ["ZERO_DISTORTION_MARKER", "RosCameraInfo", "camera_info_to_yaml", "dump_ros_pair", "ros_pair_from_profile"]

FloatArray = NDArray[np.float64]
#: The last distortion coefficient written for a camera with zero distortion and a rectifying R or P != K
#: (see the module docstring): image_proc rectifies only when some coefficient is non-zero.
ZERO_DISTORTION_MARKER = 1e-20


@dataclass(frozen=True, eq=False)
class RosCameraInfo:
    """One ROS camera_info: image size (pixels), K (3x3), D, distortion model, R (3x3), P (3x4).

    ``R`` rotates the camera's optical frame into the rectified frame; ``P = K' [I | t]`` projects
    rectified-frame points (metres) to rectified pixels; a rectified right camera has ``P[0, 3] = -fx' B``.
    ``s2r`` holds what camera_info cannot say (``convention``, ``matcher``, ``frame_id``, ``zero_distortion``).
    ``rectified`` is False for a file with neither R nor P (one camera's intrinsics: R = I, P = [K | 0] stand in).
    """

    camera_name: str
    width: int
    height: int
    K: FloatArray
    D: FloatArray
    distortion_model: str
    R: FloatArray
    P: FloatArray
    frame_id: str = ""
    s2r: dict[str, Any] = field(default_factory=dict)
    rectified: bool = True

    @property
    def image_size(self) -> tuple[int, int]:
        """``(width, height)`` in pixels."""
        return (self.width, self.height)


def ros_pair_from_profile(profile: StereoProfile, *, alpha: float = 0.0) -> tuple[RosCameraInfo, RosCameraInfo]:
    """The left and right camera_info of a profile's rectified pair (``alpha`` as in stereoRectify)."""
    from s2r.rectification import stereo_rectification  # local: reading camera_info needs no OpenCV

    problem = baseline_layout_problem(-profile.R.T @ profile.T)  # the right camera in the left optical frame
    if problem is not None:
        raise FormatError(f"[{problem[0]}] {problem[1]}: its rectified camera_info would be unusable",
                          field="extrinsics", hint="fix the profile's R and T (s2r lint shows the fix for a robot "
                          "description); a ROS stereo pair needs the right camera to the right of the left one")
    rect = stereo_rectification(profile, alpha=alpha)
    fx_rect, tx, ty = float(rect.P1[0, 0]), float(rect.P2[0, 3]), float(rect.P2[1, 3])
    fx_raw = min(profile.left.fx_px, profile.right.fx_px)
    if not (np.isfinite(rect.P1).all() and np.isfinite(rect.P2).all()) or not 0.2 * fx_raw < fx_rect < 5 * fx_raw \
            or (tx >= 0 and abs(tx) >= abs(ty)):  # a vertical pair (|ty| > |tx|) is a valid rectified pair too
        raise FormatError(f"rectification gives fx' = {fx_rect:.6g} px and Tx = {tx:.6g} (raw fx {fx_raw:.6g} px): "
                          "the camera_info would be unusable", field="extrinsics",
                          hint="check the profile's R and T: the cameras must look the same way, side by side")
    frame_id = profile.left.frame_id or profile.right.frame_id  # one frame for both: stereo_image_proc asserts it
    block: dict[str, Any] = {"convention": profile.provenance.convention, "frame_id": frame_id,
                             "matcher": profile.matcher.model_dump(mode="json")}
    infos = []
    for side, cam, R, P in (("left", profile.left, rect.R1, rect.P1), ("right", profile.right, rect.R2, rect.P2)):
        D, marked = _rectifiable_distortion(cam, R, P)
        infos.append(RosCameraInfo(
            camera_name=f"{profile.name}/{side}", width=cam.width_px, height=cam.height_px, K=cam.K, D=D,
            distortion_model=cam.distortion.model, R=R, P=P, frame_id=frame_id,
            s2r={**block, "zero_distortion": True} if marked else dict(block),
        ))
    return infos[0], infos[1]


def _rectifiable_distortion(cam: Camera, R: FloatArray, P: FloatArray) -> tuple[FloatArray, bool]:
    """``(D, marked)``: the camera's coefficients, the last one set to :data:`ZERO_DISTORTION_MARKER` when all are
    zero yet rectification moves pixels (R is not the identity or P's 3x3 block differs from K), so image_proc
    and image_geometry rectify instead of passing the raw image through."""
    D = np.array(cam.D, dtype=np.float64)
    identity = np.allclose(R, np.eye(3), rtol=0.0, atol=1e-12) and np.allclose(P[:, :3], cam.K, rtol=1e-12,
                                                                                 atol=1e-9)
    if np.any(D != 0.0) or identity:
        return D, False
    D[-1] = ZERO_DISTORTION_MARKER
    return D, True


def _matrix_block(array: FloatArray) -> dict[str, Any]:
    rows, cols = (1, array.size) if array.ndim == 1 else array.shape
    return {"rows": int(rows), "cols": int(cols), "data": [float(v) for v in array.reshape(-1)]}


def camera_info_to_yaml(info: RosCameraInfo) -> str:
    """The camera_calibration_parsers YAML text of ``info`` (numbers at full float precision)."""
    data: dict[str, Any] = {
        "image_width": info.width, "image_height": info.height, "camera_name": info.camera_name,
        "camera_matrix": _matrix_block(info.K), "distortion_model": info.distortion_model,
        "distortion_coefficients": _matrix_block(info.D), "rectification_matrix": _matrix_block(info.R),
        "projection_matrix": _matrix_block(info.P),
    }
    text = yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=1000)
    if not info.s2r:
        return text
    note = ("# s2r: what camera_info cannot say (ROS ignores it, s2r reads it back)."
            + (f" The last distortion coefficient {ZERO_DISTORTION_MARKER:g} stands for 0: image_proc rectifies "
               "only when some coefficient is non-zero." if info.s2r.get("zero_distortion") else "") + "\n")
    return text + note + yaml.safe_dump({"s2r": info.s2r}, sort_keys=False, default_flow_style=None, width=1000)


def dump_ros_pair(
    profile: StereoProfile, folder: str | Path, *, force: bool = False, alpha: float = 0.0,
    extra: dict[str, str] | None = None,
) -> tuple[Path, ...]:
    """Write ``left.yaml`` and ``right.yaml`` (rectified camera_info), then each ``extra`` file (name -> text),
    into ``folder``, all or none (staged, then published together); none overwritten without ``force``."""
    out = Path(folder)
    texts = dict(zip(("left.yaml", "right.yaml"), (camera_info_to_yaml(info) for info in ros_pair_from_profile(
        profile, alpha=alpha)), strict=True))
    texts.update(extra or {})
    for name in texts:
        check_output_free(out / name, force=force)
    prepare_output_dir(out, force=True, replace=False)  # a folder of the user's: only the named files
    with OutputBatch(force=force, root=out) as batch:
        for name, text in texts.items():
            batch.add_text(out / name, text)
        return tuple(batch.publish())
