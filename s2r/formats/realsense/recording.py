"""A librealsense recording (``.db3`` of librealsense 2.56+, or the ROS 1 ``.bag`` of older releases) as a stereo
profile: the two infrared imagers' intrinsics, distortion and extrinsics as the recording states them, the depth
scale, and the camera's name, serial number and firmware as provenance.

Both layouts name their topics after the stream (librealsense's ``ros_file_format.h``):
``/device_D/sensor_S/<Type>_<index>/...`` with ``Infrared_1`` the left imager, ``Infrared_2`` the right one and
``Depth_0`` the depth stream. Each stream's extrinsic (``.../tf/<group>``) maps points from its group's reference
(pin) stream into the stream: ``X_stream = R X_ref + t`` (metres), R column-major in storage as ``rs2_extrinsics``
keeps it (``rsutil.h``: ``to[i] = rotation[j*3 + i] * from[j] + translation[i]``). The pair's OpenCV extrinsics
follow as ``R = R2 R1^T``, ``T = t2 - R t1`` (``X_right = R X_left + T``); with Infrared 1 as the reference
(as librealsense records a D4xx) that is Infrared 2's own extrinsic. ``/tf_static`` holds the inverse transforms
(parent = reference, ROS's child pose in its parent) and is not read.

The layout readers (:mod:`s2r.formats.realsense.db3`, :mod:`s2r.formats.realsense.bag`) turn a file into
:class:`~s2r.formats.realsense.facts.RecordingFacts` (:mod:`s2r.formats.realsense.facts`); this module picks the
reader by content and builds the profile from the facts.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.errors import FormatError
from s2r.formats._common import build_stereo, provenance_for
from s2r.formats.realsense.facts import (
    BAG_MAGIC,
    HINT,
    LEFT_STREAM,
    RIGHT_STREAM,
    SQLITE_MAGIC,
    RecordingFacts,
    file_head,
)
from s2r.formats.realsense.text import camera_from_intrinsic
from s2r.profile import StereoProfile

__all__ = ["load_realsense_recording", "open_messages", "pair_extrinsics", "read_recording"]

log = logging.getLogger(__name__)
FloatArray = NDArray[np.float64]

def read_recording(path: str | Path) -> RecordingFacts:
    """The facts of a librealsense recording, from its content (SQLite: ROS 2 layout; ``#ROSBAG``: ROS 1)."""
    source = Path(path)
    head = file_head(source, 16)
    if head.startswith(SQLITE_MAGIC):
        from s2r.formats.realsense.db3 import read_db3_facts

        return read_db3_facts(source)
    if head.startswith(BAG_MAGIC):
        from s2r.formats.realsense.bag import read_bag_facts

        return read_bag_facts(source)
    raise FormatError("not a librealsense recording (neither an SQLite .db3 nor a ROS 1 .bag)", path=source,
                      hint=HINT)


def open_messages(facts: RecordingFacts) -> Any:
    """The recording's messages (a context manager with ``rows(topics)`` and ``load(row, limit=...)``), for the
    layout ``facts`` were read from."""
    if facts.layout == "ros2-sqlite3":
        from s2r.formats.realsense.db3 import Db3Recording

        return Db3Recording(facts.path)
    from s2r.formats.realsense.bag import BagRecording

    return BagRecording(facts.path)


def pair_extrinsics(facts: RecordingFacts, left: str = LEFT_STREAM, right: str = RIGHT_STREAM
                    ) -> tuple[FloatArray, FloatArray]:
    """OpenCV ``(R, T)`` of the pair, ``X_right = R X_left + T`` (T in metres), from the streams' extrinsics to
    their common reference stream (see the module docstring); FormatError when one is missing."""
    a, b = facts.stream(left), facts.stream(right)
    for name, s in ((left, a), (right, b)):
        if s.R_from_ref is None or s.t_from_ref is None or s.ref_group is None:
            raise FormatError(f"the recording holds no extrinsic of {name}", path=facts.path,
                              field=f"{s.prefix}/tf", hint="record with librealsense, which writes them")
    assert a.R_from_ref is not None and b.R_from_ref is not None  # for mypy: checked above
    assert a.t_from_ref is not None and b.t_from_ref is not None
    if a.ref_group != b.ref_group:
        raise FormatError(f"{left} and {right} have no common reference (extrinsic groups {a.ref_group} and "
                          f"{b.ref_group})", path=facts.path, field=f"{b.prefix}/tf",
                          hint="the two imagers must belong to one device's extrinsic group")
    R = b.R_from_ref @ a.R_from_ref.T
    return R, b.t_from_ref - R @ a.t_from_ref


def _provenance_notes(facts: RecordingFacts) -> str:
    dev = facts.device
    parts = [f"factory calibration as a librealsense recording ({facts.layout}) states it"]
    who = " ".join(v for v in (dev.get("Name", ""), f"S/N {dev['Serial Number']}" if dev.get("Serial Number")
                               else "", f"firmware {dev['Firmware Version']}" if dev.get("Firmware Version")
                               else "") if v)
    if who:
        parts.append(who)
    if facts.depth_units_m is not None:
        parts.append(f"depth units {facts.depth_units_m:.9g} m")
    return "; ".join(parts)


def load_realsense_recording(path: str | Path, *, name: str | None = None, origin: str = "real") -> StereoProfile:
    """A stereo profile of the recording's infrared pair (Infrared 1 left, Infrared 2 right), as recorded.

    The profile's frame_ids are realsense2_camera's (``camera_infra1_optical_frame``); the serial number,
    firmware and depth scale go to ``provenance.notes``.
    """
    facts = read_recording(path)
    cams = []
    for stream, frame_id in ((LEFT_STREAM, "camera_infra1_optical_frame"),
                             (RIGHT_STREAM, "camera_infra2_optical_frame")):
        intr = facts.stream(stream).intrinsic
        if intr is None:
            raise FormatError(f"the recording holds no intrinsics of {stream}", path=facts.path,
                              field=f"{facts.stream(stream).prefix}/camera_info", hint=HINT)
        cams.append(camera_from_intrinsic(intr, facts.path, frame_id))
    R, T = pair_extrinsics(facts)
    size = cams[0].image_size
    serial = facts.device.get("Serial Number", "")
    default = f"realsense_{serial}_{size[0]}x{size[1]}" if serial else f"realsense_{size[0]}x{size[1]}"
    method = "librealsense recording (ROS 2 sqlite3)" if facts.layout == "ros2-sqlite3" else \
        "librealsense recording (ROS 1 bag)"
    return build_stereo(
        name=name or default, left=cams[0], right=cams[1], R=R, T=T, path=facts.path,
        provenance=provenance_for([facts.path], method, origin=origin, notes=_provenance_notes(facts)),
        description=f"{facts.device.get('Name') or 'RealSense'} Infrared 1 + Infrared 2 at {size[0]}x{size[1]} "
                    "(factory calibration, from a recording)",
    )
