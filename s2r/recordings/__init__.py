"""Recordings: every input that yields stereo frames (folders, globs, bags, videos, RealSense recordings), defined
once and streamed.

Commands never open frame files themselves: they describe the recording as a :class:`RecordingSpec` (the CLI builds
it from one argument group, ``s2r.cli._recording``) and iterate :class:`StereoFrame` values from
:func:`open_recording`, each carrying its name, stamp and frame_id, decoded one at a time after the declared image
size was checked against the expected one::

    from s2r.recordings import open_recording
    for frame in open_recording(video="sbs.mp4", layout="sbs", every=5, expected_size=(640, 480)).frames():
        ...  # frame.left, frame.right: uint8 images; frame.name, frame.stamp_ns, frame.frame_id

Layer: above ``imageio``/``profile``/``formats`` (it reads files and bags), below calib, depth, quality, drift,
sensor_fit and validate, which consume frames. It imports no pipeline, solver or renderer.
"""

from __future__ import annotations

from s2r.recordings.frames import (
    NAMED_SKIPPED,
    FrameSource,
    StereoFrame,
    refuse_same_sides,
    skipped_fields,
    skipped_inputs,
)
from s2r.recordings.spec import RecordingSpec, open_recording

__all__ = ["NAMED_SKIPPED", "FrameSource", "RecordingSpec", "StereoFrame", "open_recording", "refuse_same_sides",
           "skipped_fields", "skipped_inputs"]
