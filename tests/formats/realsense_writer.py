"""Test recordings written by Intel's own pyrealsense2 (software_device + recorder): no camera, no s2r code.

Two infrared streams with known, distinct intrinsics and distortion, a depth stream, a non-identity Infrared 1 ->
Infrared 2 extrinsic (``register_extrinsics_to``, rotation column-major as ``rs2_extrinsics`` stores it), a depth
scale option and the device's name, serial and firmware. Frames are seeded random textures.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest


def pyrealsense2() -> Any:
    """The pyrealsense2 module, or a skip with the reason (absent, or its libusb missing)."""
    try:
        import pyrealsense2 as rs
    except (ImportError, OSError) as exc:
        pytest.skip(f"pyrealsense2 not usable here ({exc}); apt-get install libusb-1.0-0 / pip install pyrealsense2")
    return rs


def rotation(axis: tuple[float, float, float], angle: float) -> np.ndarray:
    """Rodrigues' formula, written out (shares nothing with s2r)."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


@dataclass
class Spec:
    """What the recording is made with."""

    width: int = 64
    height: int = 48
    ir1: tuple[float, ...] = (40.123456, 40.5, 31.25, 23.75)  # fx fy ppx ppy
    ir2: tuple[float, ...] = (41.0, 41.25, 32.5, 24.125)
    d1: tuple[float, ...] = (0.1, -0.2, 0.001, 0.002, 0.03)
    d2: tuple[float, ...] = (-0.05, 0.07, -0.003, 0.004, -0.01)
    R: np.ndarray = field(default_factory=lambda: rotation((0.3, 1.0, -0.2), 0.02))
    t: tuple[float, float, float] = (-0.05, 0.001, 0.002)
    depth_units: float = 0.00025
    frames: int = 4
    drop_right: tuple[int, ...] = ()
    compress: bool = True
    seed: int = 3


def write(path: Path, spec: Spec) -> list[tuple[np.ndarray, np.ndarray]]:
    """Record ``spec`` to ``path`` (.db3); the (left, right) images pushed, per frame number."""
    rs = pyrealsense2()
    dev = rs.software_device()
    dev.register_info(rs.camera_info.serial_number, "123456789012")
    dev.register_info(rs.camera_info.firmware_version, "5.16.0.1")
    dev.register_info(rs.camera_info.name, "Intel RealSense D435")
    sensor = dev.add_sensor("Stereo Module")

    def stream(uid: int, index: int, kind: Any, fmt: Any, bpp: int, k: tuple, d: tuple) -> Any:
        intr = rs.intrinsics()
        intr.width, intr.height = spec.width, spec.height
        intr.fx, intr.fy, intr.ppx, intr.ppy = k
        intr.model, intr.coeffs = rs.distortion.brown_conrady, list(d)
        vs = rs.video_stream()
        vs.type, vs.index, vs.uid, vs.width, vs.height = kind, index, uid, spec.width, spec.height
        vs.fps, vs.bpp, vs.fmt, vs.intrinsics = 30, bpp, fmt, intr
        return sensor.add_video_stream(vs, uid == 1)

    p1 = stream(1, 1, rs.stream.infrared, rs.format.y8, 1, spec.ir1, spec.d1)
    p2 = stream(2, 2, rs.stream.infrared, rs.format.y8, 1, spec.ir2, spec.d2)
    pd = stream(3, 0, rs.stream.depth, rs.format.z16, 2, spec.ir1, spec.d1)
    sensor.add_read_only_option(rs.option.depth_units, spec.depth_units)
    ext = rs.extrinsics()
    ext.rotation = [float(v) for v in spec.R.T.ravel()]  # column-major
    ext.translation = list(spec.t)
    p1.register_extrinsics_to(p2, ext)
    recorder = rs.recorder(str(path), dev, spec.compress)
    rec_sensor = recorder.query_sensors()[0]
    rec_sensor.open([p1, p2, pd])
    queue = rs.frame_queue(100)
    rec_sensor.start(queue)
    rng = np.random.default_rng(spec.seed)
    pushed = []
    for n in range(spec.frames):
        left = rng.integers(0, 256, (spec.height, spec.width), dtype=np.uint8)
        right = rng.integers(0, 256, (spec.height, spec.width), dtype=np.uint8)
        depth = rng.integers(0, 5000, (spec.height, spec.width), dtype=np.uint16)
        pushed.append((left, right))
        for prof, pixels, bpp, delay in ((p1, left, 1, 0.0), (p2, right, 1, 3.0), (pd, depth, 2, 0.0)):
            if prof is p2 and n in spec.drop_right:
                continue
            frame = rs.software_video_frame()
            frame.pixels, frame.bpp, frame.stride = pixels, bpp, spec.width * bpp
            frame.timestamp, frame.frame_number = 1000.0 + 33.3 * n + delay, n
            frame.domain, frame.profile = rs.timestamp_domain.hardware_clock, prof.as_video_stream_profile()
            if prof is pd:
                frame.depth_units = spec.depth_units
            sensor.on_video_frame(frame)
        time.sleep(0.02)
    rec_sensor.stop()
    rec_sensor.close()
    del rec_sensor, recorder
    return pushed


def playback(path: Path) -> dict[str, Any]:
    """What pyrealsense2 itself reads back from ``path``: intrinsics, extrinsics, depth scale, device info."""
    rs = pyrealsense2()
    dev = rs.context().load_device(str(path))
    sensor = dev.query_sensors()[0]
    profiles = {p.stream_name(): p for p in sensor.get_stream_profiles()}
    ir1, ir2 = profiles["Infrared 1"], profiles["Infrared 2"]
    ext = ir1.get_extrinsics_to(ir2)
    return {
        "ir1": ir1.as_video_stream_profile().get_intrinsics(), "ir2": ir2.as_video_stream_profile().get_intrinsics(),
        "rotation": list(ext.rotation), "translation": list(ext.translation), "extrinsics": ext,
        "depth_scale": sensor.as_depth_sensor().get_depth_scale(), "rs": rs,
        "serial": dev.get_info(rs.camera_info.serial_number), "firmware": dev.get_info(rs.camera_info.firmware_version),
        "name": dev.get_info(rs.camera_info.name),
    }
