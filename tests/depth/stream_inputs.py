"""Stream test inputs: a known-depth sequence from tests/raycast.py (an independent ray caster: its own lens maths,
numpy and cv2 only, no s2r import), written as a folder of PNGs and as a ROS 2 bag by rosbags itself."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from s2r.formats.s2r_yaml import dump_profile
from s2r.profile import Camera, Distortion, Extrinsics, Provenance, StereoProfile
from tests import raycast as rc

F64 = NDArray[np.float64]
LEFT_TOPIC, RIGHT_TOPIC = "/cam/left/image_raw", "/cam/right/image_raw"
FRAME_ID = "raycast_left_optical"
#: The rectified left frame every depth output is labelled with (REP 103's _optical suffix kept last).
RECT_FRAME_ID = "raycast_left_rect_optical"
#: Input stamps of the bag: not evenly spaced, so a synthesized stamp could not pass for them.
STAMPS_NS = (1_700_000_000_000_000_000, 1_700_000_000_033_000_000, 1_700_000_000_071_500_000)


@dataclass(frozen=True)
class KnownFrame:
    left: NDArray[np.uint8]
    right: NDArray[np.uint8]
    normal: F64  # the plane's normal in the left camera frame
    offset_m: float  # normal . X = offset_m for points X of the plane (left camera frame, metres)


def _camera(lens: rc.Lens, frame_id: str) -> Camera:
    return Camera(width_px=lens.width, height_px=lens.height, fx_px=lens.fx, fy_px=lens.fy, cx_px=lens.cx,
                  cy_px=lens.cy, distortion=Distortion(coefficients=lens.dist), frame_id=frame_id)


def speckle_plane(seed: int = 3) -> rc.Target:
    """A 4.8 m square speckle texture (8 mm texels, blurred so block matchers lock on)."""
    rng = np.random.default_rng(seed)
    tex = cv2.GaussianBlur(rng.integers(0, 256, (600, 600), dtype=np.uint8), (3, 3), 0)
    return rc.Target(kind="speckle", texture=np.asarray(tex, np.uint8), texel_m=0.008, y_up=False,
                     ids=np.zeros(0, np.int64), points=np.zeros((0, 3)), yaml="", extent=(-2.4, -2.4, 2.4, 2.4))


def known_rig() -> tuple[rc.Rig, StereoProfile]:
    """raycast's pinhole rig at 320x240 (plumb_bob lenses, 8 cm baseline, turned right camera) and its profile."""
    rig = rc.pinhole_rig(speckle_plane(), "stream", scale=0.5)
    profile = StereoProfile(name="raycast_stream", left=_camera(rig.left, FRAME_ID),
                            right=_camera(rig.right, "raycast_right_optical"),
                            extrinsics=Extrinsics(rotation=tuple(map(tuple, rig.R.tolist())),
                                                  translation_m=tuple(np.asarray(rig.T).tolist())),
                            provenance=Provenance(origin="sim", method="tests.raycast", convention="exact"))
    return rig, profile


def known_frames(rig: rc.Rig, distances_m: tuple[float, ...] = (0.9, 1.3, 1.8)) -> list[KnownFrame]:
    """A slanted plane (turned 25-35 deg about y and 10 deg about x, so every sub-pixel phase occurs) at each
    distance along the left optical axis."""
    frames = []
    for k, z in enumerate(distances_m):
        R_lb = Rotation.from_euler("yx", [25.0 + 5 * k, 10.0], degrees=True).as_matrix()
        t_lb = np.array([0.0, 0.0, z])
        left = rc.render(rig.left, rig.target, R_lb, t_lb, seed=10 + k, noise=1.0)
        right = rc.render(rig.right, rig.target, rig.R @ R_lb, rig.R @ t_lb + np.asarray(rig.T), seed=20 + k,
                          noise=1.0)
        normal = R_lb[:, 2]
        frames.append(KnownFrame(left, right, normal, float(normal @ t_lb)))
    return frames


def truth_depth(frame: KnownFrame, P1: F64, R1: F64, shape: tuple[int, int]) -> F64:
    """Depth (m) along the rectified left axis at every rectified pixel: the ray of pixel (u, v) of ``P1`` turned
    back by ``R1`` into the left camera frame, met with the plane."""
    h, w = shape
    vs, us = np.mgrid[0:h, 0:w].astype(np.float64)
    rays = np.stack([(us - P1[0, 2]) / P1[0, 0], (vs - P1[1, 2]) / P1[1, 1], np.ones_like(us)], axis=-1)
    raw = rays @ R1  # R1^T applied to each ray (rows)
    return frame.offset_m / (raw @ frame.normal)


def write_folder(frames: list[KnownFrame], folder: Path) -> list[str]:
    """``folder/left/NAME.png`` and ``folder/right/NAME.png``; the names."""
    names = [f"shot_{k:02d}" for k in range(len(frames))]
    for side in ("left", "right"):
        (folder / side).mkdir(parents=True)
        for name, frame in zip(names, frames, strict=True):
            cv2.imwrite(str(folder / side / f"{name}.png"), getattr(frame, side))
    return names


def write_ros2_bag(frames: list[KnownFrame], path: Path, *, frame_id: str = "input_cam") -> None:
    """The frames as mono8 Images on two topics of a ROS 2 (sqlite3) bag, written by rosbags, labelled
    ``frame_id``."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    image, header, time = (store.types[n] for n in ("sensor_msgs/msg/Image", "std_msgs/msg/Header",
                                                    "builtin_interfaces/msg/Time"))
    with Writer(path, version=9) as writer:
        conns = {t: writer.add_connection(t, "sensor_msgs/msg/Image", typestore=store) for t in (LEFT_TOPIC,
                                                                                                 RIGHT_TOPIC)}
        for frame, stamp in zip(frames, STAMPS_NS, strict=False):
            for topic, img in ((LEFT_TOPIC, frame.left), (RIGHT_TOPIC, frame.right)):
                hdr = header(stamp=time(sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id=frame_id)
                msg = image(header=hdr, height=img.shape[0], width=img.shape[1], encoding="mono8", is_bigendian=0,
                            step=img.shape[1], data=np.ascontiguousarray(img).reshape(-1))
                writer.write(conns[topic], stamp, store.serialize_cdr(msg, "sensor_msgs/msg/Image"))


def write_profile(profile: StereoProfile, path: Path) -> Path:
    dump_profile(profile, path)
    return path
