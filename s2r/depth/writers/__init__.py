"""Outputs of depth streams: one writer per target behind one interface, fed by :func:`s2r.depth.stream.depth_frames`.

- ``files`` (:mod:`.files`): per-frame files named after the input frame, and ``frames.csv``;
- ``ros2`` / ``ros1`` (:mod:`.rosbag`): a ROS 2 bag folder (mcap storage) or a ROS 1 ``.bag``, written by rosbags
  with the messages of :mod:`.ros_messages`.

Every writer publishes whole or not at all: nothing appears at the output until :meth:`StreamWriter.publish`,
and leaving the ``with`` block without publishing (an error, an interrupt) removes everything staged.

Layer: inside ``s2r.depth``; imports the depth pipeline's results, ``s2r.fileio`` and (for bags) rosbags.
"""

from __future__ import annotations

from s2r.depth.writers.base import TARGETS, StreamOptions, StreamWriter, open_writer, write_stream

__all__ = ["TARGETS", "StreamOptions", "StreamWriter", "open_writer", "write_stream"]
