"""ROS messages of one depth frame, built with rosbags' typestores (ROS 2 Humble or ROS 1 Noetic definitions).

Conventions (stereo_image_proc, depth_image_proc, REP 118), every message stamped with the input left image's
stamp and labelled with ONE frame_id (stereo_image_proc asserts that both cameras share it): the RECTIFIED left
camera's frame, ``<left>_rect_optical_frame`` (:func:`s2r.depth.stream.rectified_frame_id`), which is where the
data are. stereo_image_proc labels its outputs with the left optical frame itself, which leaves the
rectification's rotation R1 out of tf (points come out turned by up to a degree or more); here it is on
``/tf_static``, so tf consumers place depth and points where they are:

- ``left/image_rect`` (mono8) or ``left/image_rect_color`` (bgr8): the rectified left image the matcher saw;
- ``left/camera_info``, ``right/camera_info``: the RECTIFIED pair (K = P[:, :3], no distortion, R = I, P = P1 /
  P2 with the right Tx = -fx' B), so the rectified images and the disparity are used as they are;
- ``disparity``: stereo_msgs/DisparityImage, 32FC1 ``d = x_left - x_right - (cx_left - cx_right)`` so that
  ``Z = f T / d``; invalid pixels hold ``min_disparity - 1`` (as stereo_image_proc writes them), delta_d 1/16;
- ``depth/image_rect`` 32FC1 metres (NaN invalid) or 16UC1 millimetres (0 invalid), and ``depth/camera_info``;
- ``points2``: organised PointCloud2 (x y z float32 metres, rgb packed as float32, NaN invalid), as
  stereo_image_proc's;
- ``/tf_static``: the right optical frame's pose in the left one (from the profile's R, T), and the rectified
  frame's in the left optical one (rotation R1^T, no translation).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from s2r.depth.outputs import depth_to_mm
from s2r.depth.pipeline import DepthResult
from s2r.profile import StereoProfile
from s2r.rectification import StereoRectification

__all__ = ["DEPTH_ENCODINGS", "RosMessages", "organised_cloud"]

#: Depth image encodings: metres as float (REP 118's default) or millimetres as uint16.
DEPTH_ENCODINGS = ("32FC1", "16UC1")


def organised_cloud(result: DepthResult) -> NDArray[np.float32]:
    """(H, W, 4) float32: x y z metres in the rectified left optical frame (NaN invalid) and rgb packed as the
    float32 whose bits are ``0x00RRGGBB`` (PCL's and stereo_image_proc's layout)."""
    h, w = result.disparity.shape
    vs, us = np.mgrid[0:h, 0:w].astype(np.float64)
    pix = np.stack([us, vs, np.nan_to_num(result.disparity.astype(np.float64), nan=1.0), np.ones_like(us)], axis=-1)
    hom = pix @ np.asarray(result.Q, np.float64).T
    xyz = (hom[..., :3] / hom[..., 3:4]).astype(np.float32)
    xyz[~result.valid] = np.nan
    img = result.rect_left
    bgr = np.repeat(img[..., None], 3, axis=2) if img.ndim == 2 else img
    packed = (bgr[..., 2].astype(np.uint32) << 16) | (bgr[..., 1].astype(np.uint32) << 8) | bgr[..., 0]
    return np.ascontiguousarray(np.concatenate([xyz, packed.view(np.float32)[..., None]], axis=-1))


@dataclass(frozen=True)
class RosMessages:
    """Builds the messages of one bag flavour: ``ros1`` (Noetic field names, header seq) or ``ros2`` (Humble)."""

    typestore: Any
    ros1: bool

    def _t(self, name: str) -> Any:
        return self.typestore.types[name]

    def _names(self, **fields: Any) -> dict[str, Any]:
        """ROS 1's CameraInfo / DisparityImage spell D K R P T in capitals; ROS 2's in lower case."""
        if not self.ros1:
            return fields
        return {k.upper() if k in ("d", "k", "r", "p", "t") else k: v for k, v in fields.items()}

    def header(self, stamp_ns: int, frame_id: str, seq: int = 0) -> Any:
        stamp = self._t("builtin_interfaces/msg/Time")(sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000)
        if self.ros1:
            return self._t("std_msgs/msg/Header")(seq=seq, stamp=stamp, frame_id=frame_id)
        return self._t("std_msgs/msg/Header")(stamp=stamp, frame_id=frame_id)

    def image(self, header: Any, array: NDArray[Any], encoding: str) -> Any:
        data = np.ascontiguousarray(array)
        step = int(data.shape[1] * data.itemsize * (data.shape[2] if data.ndim == 3 else 1))
        return self._t("sensor_msgs/msg/Image")(header=header, height=int(data.shape[0]), width=int(data.shape[1]),
                                                encoding=encoding, is_bigendian=0, step=step,
                                                data=data.view(np.uint8).reshape(-1))

    def roi(self, width: int = 0, height: int = 0) -> Any:
        return self._t("sensor_msgs/msg/RegionOfInterest")(x_offset=0, y_offset=0, height=height, width=width,
                                                           do_rectify=False)

    def camera_info(self, header: Any, rect: StereoRectification, *, right: bool = False) -> Any:
        P = np.asarray(rect.P2 if right else rect.P1, np.float64)
        width, height = (int(v) for v in rect.image_size)
        return self._t("sensor_msgs/msg/CameraInfo")(
            header=header, height=height, width=width, distortion_model="plumb_bob", binning_x=0, binning_y=0,
            roi=self.roi(), **self._names(d=np.zeros(5), k=P[:, :3].reshape(-1).copy(), r=np.eye(3).reshape(-1),
                                          p=P.reshape(-1).copy()))

    def disparity(self, header: Any, result: DepthResult, rect: StereoRectification, *, min_disparity: int,
                  num_disparities: int) -> Any:
        low = float(min_disparity) + float(rect.doffs_px)
        image = np.where(result.valid, result.disparity + np.float32(rect.doffs_px), np.float32(low - 1.0))
        h, w = image.shape
        return self._t("stereo_msgs/msg/DisparityImage")(
            header=header, image=self.image(header, image.astype(np.float32), "32FC1"),
            valid_window=self.roi(w, h), min_disparity=low, max_disparity=low + num_disparities - 1,
            delta_d=1.0 / 16.0, **self._names(f=float(rect.fx_px), t=float(rect.baseline_m)))

    def depth(self, header: Any, result: DepthResult, encoding: str) -> Any:
        if encoding == "16UC1":
            return self.image(header, depth_to_mm(result.depth), "16UC1")
        return self.image(header, np.asarray(result.depth, np.float32), "32FC1")

    def points(self, header: Any, result: DepthResult) -> Any:
        cloud = organised_cloud(result)
        h, w = cloud.shape[:2]
        field = self._t("sensor_msgs/msg/PointField")
        fields = [field(name=n, offset=4 * k, datatype=7, count=1) for k, n in enumerate(("x", "y", "z", "rgb"))]
        return self._t("sensor_msgs/msg/PointCloud2")(
            header=header, height=h, width=w, fields=fields, is_bigendian=False, point_step=16, row_step=16 * w,
            data=cloud.view(np.uint8).reshape(-1), is_dense=False)

    def _transform(self, stamp_ns: int, parent: str, child: str, rotation: NDArray[np.float64],
                   translation: NDArray[np.float64]) -> Any:
        """TransformStamped of ``child`` in ``parent``: ``X_parent = rotation X_child + translation`` (metres)."""
        x, y, z, w = Rotation.from_matrix(rotation).as_quat()
        tx, ty, tz = (float(v) for v in translation)
        transform = self._t("geometry_msgs/msg/Transform")(
            translation=self._t("geometry_msgs/msg/Vector3")(x=tx, y=ty, z=tz),
            rotation=self._t("geometry_msgs/msg/Quaternion")(x=float(x), y=float(y), z=float(z), w=float(w)))
        return self._t("geometry_msgs/msg/TransformStamped")(
            header=self.header(stamp_ns, parent), child_frame_id=child, transform=transform)

    def tf_static(self, stamp_ns: int, profile: StereoProfile, left_frame: str, right_frame: str, *,
                  rect_frame: str, R1: NDArray[np.float64]) -> Any:
        """TFMessage: the right optical frame in the left one (``X_left = R^T X_right - R^T T``) and the rectified
        left frame in the left optical one (``X_left = R1^T X_rect``: the rectification turns, never moves); no
        rectified frame when it is the left frame itself (input rectified already, its name kept: a transform of a
        frame into itself is a loop in tf)."""
        R, T = np.asarray(profile.R, np.float64), np.asarray(profile.T, np.float64).reshape(3)
        transforms = [self._transform(stamp_ns, left_frame, right_frame, R.T, -R.T @ T)]
        if rect_frame != left_frame:
            transforms.append(self._transform(stamp_ns, left_frame, rect_frame, np.asarray(R1, np.float64).T,
                                              np.zeros(3)))
        return self._t("tf2_msgs/msg/TFMessage")(transforms=transforms)

    def serialize(self, message: Any) -> bytes:
        kind = message.__msgtype__
        data = (self.typestore.serialize_ros1(message, kind) if self.ros1
                else self.typestore.serialize_cdr(message, kind))
        return bytes(data)
