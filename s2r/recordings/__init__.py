"""Recordings: every input that yields stereo frames (folders, globs, bags, videos, RealSense recordings), defined
once and streamed.

Commands never open frame files themselves: they take a :class:`RecordingSpec`-like description from the CLI and
iterate :class:`StereoFrame` values, each carrying its name, stamp and frame_id, decoded one at a time after the
declared image size was checked against the expected one.

Layer: above ``imageio``/``profile``/``formats`` (it reads files and bags), below calib, depth, quality, drift,
sensor_fit and validate, which consume frames. It imports no pipeline, solver or renderer.
"""

from __future__ import annotations

from s2r.recordings.frames import FrameSource, StereoFrame

__all__ = ["FrameSource", "StereoFrame"]
