"""``s2r depth --to files``: per-frame files named after the input frame, and an index mapping each to its input.

Layout of OUT (``NAME`` is :attr:`StereoFrame.name`: the left file's stem, a bag stamp, ``frame_000123``):

- ``depth/NAME.png``: uint16 millimetres, 0 invalid; ``depth/NAME.npy``: float32 metres, NaN invalid (the exact
  values a bag's 32FC1 depth holds);
- ``disparity/NAME.npy``: float32 pixels, NaN invalid; ``color/NAME.png``: JET colouring with a bar in metres;
- ``points/NAME.ply`` (``--ply``) and ``points/NAME.pcd`` (``--pcd``): the valid points, metres, coloured;
- ``camera_info.yaml``: the rectified left camera (the frame of everything above);
- ``frames.csv``: one row per frame: index, name, stamp_ns, stamp_source (``recorded``; ``file time``: a video
  without ``--start-stamp``, stamped from its file's modification time; ``synthesized``: still files carry no time),
  frame_id (the rectified left frame, ``<left>_rect_optical_frame``: the optical frame turned by R1, as a bag's
  /tf_static says), the input (``source``), the valid fraction and every file written for it.

Everything is staged in one :class:`s2r.fileio.OutputBatch` and published together.
"""

from __future__ import annotations

import contextlib
import csv
import io
from pathlib import Path

import numpy as np

from s2r.depth.outputs import (
    depth_colour_with_bar,
    depth_to_mm,
    pcd_bytes,
    ply_bytes,
    png_bytes,
    rectified_camera_info,
)
from s2r.depth.pipeline import StereoPipeline
from s2r.depth.stream import DepthFrame
from s2r.depth.writers.base import StreamOptions, StreamWriter
from s2r.errors import DepthError
from s2r.fileio import OutputBatch, npy_bytes, prepare_output_dir
from s2r.formats.ros import camera_info_to_yaml

__all__ = ["INDEX_COLUMNS", "FilesWriter"]

#: Columns of frames.csv.
INDEX_COLUMNS = ("index", "name", "stamp_ns", "stamp_source", "frame_id", "source", "valid_fraction", "depth_png",
                 "depth_npy", "disparity_npy", "color_png", "points_ply", "points_pcd")


class FilesWriter(StreamWriter):
    """Per-frame depth files in OUT, published with ``camera_info.yaml`` and ``frames.csv`` at the end."""

    def __init__(self, out: Path, pipeline: StereoPipeline, *, force: bool, options: StreamOptions) -> None:
        super().__init__(out, pipeline, force=force, options=options)
        self._created = not self.out.exists() and not self.out.is_symlink()
        prepare_output_dir(self.out, force=self.force)
        self._batch = OutputBatch(force=self.force, root=self.out)
        self._rows: list[dict[str, object]] = []
        self._sources: dict[str, str] = {}
        self._first: DepthFrame | None = None

    def _add(self, rel: str, data: bytes) -> str:
        self._batch.add_bytes(self.out / rel, data)
        return rel

    def write(self, frame: DepthFrame) -> None:
        if frame.name in self._sources:
            raise DepthError(f"two frames are both named {frame.name!r} ({self._sources[frame.name]} and "
                             f"{frame.source}): their outputs would overwrite each other", path=frame.source,
                             hint="give inputs whose frames have distinct names")
        self._sources[frame.name] = frame.source
        r, name = frame.result, frame.name
        depth_png = self.out / f"depth/{name}.png"
        row: dict[str, object] = {
            "index": frame.index, "name": name, "stamp_ns": frame.stamp_ns,
            "stamp_source": frame.stamp_source,
            "frame_id": self.rect_frame_id(frame),
            "source": frame.source, "valid_fraction": f"{float(r.valid.mean()):.6f}",
            "depth_png": self._add(f"depth/{name}.png", png_bytes(depth_to_mm(r.depth), depth_png)),
            "depth_npy": self._add(f"depth/{name}.npy", npy_bytes(np.asarray(r.depth, np.float32))),
            "disparity_npy": self._add(f"disparity/{name}.npy", npy_bytes(np.asarray(r.disparity, np.float32))),
            "color_png": self._add(f"color/{name}.png", png_bytes(
                depth_colour_with_bar(r.disparity, r.Q, self.options.colour_range_m), depth_png)),
            "points_ply": "", "points_pcd": ""}
        if self.options.points or self.options.pcd:
            cloud = r.point_cloud()
            if self.options.points:
                row["points_ply"] = self._add(f"points/{name}.ply", ply_bytes(*cloud))
            if self.options.pcd:
                row["points_pcd"] = self._add(f"points/{name}.pcd", pcd_bytes(*cloud))
        self._rows.append(row)
        self._first = self._first or frame
        self.frames += 1

    def publish(self) -> list[Path]:
        self._check_frames()
        assert self._first is not None
        info = rectified_camera_info(self.rectification(self._first), name=f"{self.pipeline.profile.name}/"
                                     "rectified_left")
        self._batch.add_text(self.out / "camera_info.yaml", camera_info_to_yaml(info))
        text = io.StringIO()
        table = csv.DictWriter(text, fieldnames=INDEX_COLUMNS, lineterminator="\n")
        table.writeheader()
        table.writerows(self._rows)
        self._batch.add_text(self.out / "frames.csv", text.getvalue())
        return self._batch.publish()

    def discard(self) -> None:
        """Remove the staged files, and the folders this run created when they are left empty."""
        self._batch.discard()
        if not self._created:
            return
        for folder in (*(self.out / sub for sub in ("depth", "disparity", "color", "points")), self.out):
            with contextlib.suppress(OSError):  # not empty (published) or gone: leave it
                folder.rmdir()
