"""``s2r depth --to ros2|ros1``: a ROS 2 bag folder (mcap storage) or a ROS 1 ``.bag``, written by rosbags.

The bag is written in a private temporary folder beside OUT (``.s2r-tmp-*``, same filesystem) and published by
:class:`s2r.fileio.OutputBatch` only once it is complete and closed: a failure (bad frame, full disk, Ctrl-C)
leaves no half bag, and an existing OUT is replaced only with ``--force`` (never a link or a special file).

Topics under the namespace (default ``/stereo``) as :mod:`.ros_messages` lists them; ``/tf_static`` is written
once, latched (ROS 1) or with transient-local durability (ROS 2), at the first frame's stamp: the right optical
frame and the rectified left frame every message is labelled with, both in the left optical frame.
"""

from __future__ import annotations

import contextlib
import shutil
import tempfile
from pathlib import Path
from typing import Any, Final

from s2r.depth.stream import DepthFrame, frame_ids
from s2r.depth.writers.base import StreamWriter
from s2r.depth.writers.ros_messages import DEPTH_ENCODINGS, RosMessages
from s2r.errors import DepthError, S2RError
from s2r.fileio import TEMP_PREFIX, OutputBatch, check_output_dir, check_output_free, prepare_output_dir

__all__ = ["ROS2_METADATA_VERSION", "RosBagWriter", "topic_names"]

#: metadata.yaml version of ROS 2 bags: 8 (Iron's), which every supported distro reads. Jazzy writes 9, where
#: ``offered_qos_profiles`` became a YAML list; Humble's rosbag2 (0.15, which writes 5) parses that field as a
#: string and stops with "yaml-cpp: bad conversion" (ros2/rosbag2#2013). Version 8 keeps it a string of the
#: integer-valued policies Humble writes, and the keys Humble does not know (``type_description_hash``,
#: ``custom_data``, ``ros_distro``) are ignored by its reader; Jazzy reads every version up to 9. rosbags writes
#: only 8 or 9.
ROS2_METADATA_VERSION: Final = 8

#: ROS 1 Noetic has no tf2_msgs in rosbags' store: its definition, registered on the ROS 1 typestore.
_TF_MESSAGE_ROS1 = "geometry_msgs/TransformStamped[] transforms\n"


def topic_names(namespace: str, *, colour: bool) -> dict[str, str]:
    """Topic of each stream under ``namespace`` (``/stereo`` -> ``/stereo/left/image_rect``...)."""
    ns = "/" + namespace.strip("/") if namespace.strip("/") else ""
    return {"image": f"{ns}/left/image_rect_color" if colour else f"{ns}/left/image_rect",
            "left_info": f"{ns}/left/camera_info", "right_info": f"{ns}/right/camera_info",
            "disparity": f"{ns}/disparity", "depth": f"{ns}/depth/image_rect",
            "depth_info": f"{ns}/depth/camera_info", "points": f"{ns}/points2", "tf": "/tf_static"}


def _typestore(ros1: bool) -> Any:
    try:
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore
    except ImportError:
        raise DepthError("writing ROS bags needs the rosbags package", field="--to",
                         hint="pip install 's2r[ros]' (make installs it)") from None
    if not ros1:
        return get_typestore(Stores.ROS2_HUMBLE)
    store = get_typestore(Stores.ROS1_NOETIC)
    store.register(get_types_from_msg(_TF_MESSAGE_ROS1, "tf2_msgs/msg/TFMessage"))
    return store


class RosBagWriter(StreamWriter):
    """Depth frames as a ROS bag; ``ros1`` for a ROS 1 ``.bag``, else a ROS 2 bag folder with mcap storage."""

    def __init__(self, out: Path, pipeline: Any, *, ros1: bool, **kwargs: Any) -> None:
        super().__init__(out, pipeline, **kwargs)
        if self.options.depth_encoding not in DEPTH_ENCODINGS:
            raise DepthError(f"unknown depth encoding {self.options.depth_encoding!r}", field="--depth-encoding",
                             hint=f"choose one of {', '.join(DEPTH_ENCODINGS)}")
        self.ros1 = ros1
        if ros1:
            check_output_free(self.out, force=self.force)
        else:
            check_output_dir(self.out, force=self.force)
        self._messages = RosMessages(_typestore(ros1), ros1)
        try:
            self.out.parent.mkdir(parents=True, exist_ok=True)
            self._tmp = Path(tempfile.mkdtemp(prefix=TEMP_PREFIX, dir=self.out.parent))
        except OSError as exc:
            raise S2RError(f"cannot write: {exc.strerror}; nothing was written", path=self.out,
                           hint="choose a writable location") from None
        self._bag_path = self._tmp / self.out.name
        self._writer: Any = None
        self._connections: dict[str, Any] = {}

    def _open(self, frame: DepthFrame) -> None:
        """Open the bag and add every topic (the image topic's name depends on the first frame's channels)."""
        from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

        colour = frame.result.rect_left.ndim == 3
        topics = topic_names(self.options.namespace, colour=colour)
        types = {"image": "sensor_msgs/msg/Image", "left_info": "sensor_msgs/msg/CameraInfo",
                 "right_info": "sensor_msgs/msg/CameraInfo", "disparity": "stereo_msgs/msg/DisparityImage",
                 "depth": "sensor_msgs/msg/Image", "depth_info": "sensor_msgs/msg/CameraInfo",
                 "points": "sensor_msgs/msg/PointCloud2", "tf": "tf2_msgs/msg/TFMessage"}
        if not self.options.points:
            del topics["points"]
        store = self._messages.typestore
        if self.ros1:
            from rosbags.rosbag1 import Writer as Writer1

            self._writer = Writer1(self._bag_path)
            self._writer.open()
            for key, topic in topics.items():
                self._connections[key] = self._writer.add_connection(
                    topic, types[key], typestore=store, callerid="/s2r_depth", latching=1 if key == "tf" else None)
            return
        from rosbags.rosbag2 import StoragePlugin
        from rosbags.rosbag2 import Writer as Writer2

        zero = QosTime(sec=0, nsec=0)
        latched = Qos(QosHistory.KEEP_LAST, 1, QosReliability.RELIABLE, QosDurability.TRANSIENT_LOCAL, zero, zero,
                      QosLiveliness.AUTOMATIC, zero, False)
        self._writer = Writer2(self._bag_path, version=ROS2_METADATA_VERSION, storage_plugin=StoragePlugin.MCAP)
        self._writer.open()
        for key, topic in topics.items():
            self._connections[key] = self._writer.add_connection(
                topic, types[key], typestore=store, offered_qos_profiles=[latched] if key == "tf" else [])

    def _put(self, key: str, stamp_ns: int, message: Any) -> None:
        try:
            self._writer.write(self._connections[key], stamp_ns, self._messages.serialize(message))
        except OSError as exc:
            raise S2RError(f"cannot write: {exc.strerror}; nothing was written", path=self.out,
                           hint="free some space or choose a writable location") from None

    def write(self, frame: DepthFrame) -> None:
        rect_frame = self.rect_frame_id(frame)
        if self._writer is None:
            self._open(frame)
            left, right = frame_ids(frame.frame_id, self.pipeline.profile.right.frame_id, "", "")
            self._put("tf", frame.stamp_ns, self._messages.tf_static(
                frame.stamp_ns, self.pipeline.profile, left, right, rect_frame=rect_frame,
                R1=self.rectification(frame).R1))
        m, rect, stamp, r = self._messages, self.rectification(frame), frame.stamp_ns, frame.result
        header = m.header(stamp, rect_frame, seq=self.frames)
        config = self.pipeline.geometry_for(rect.image_size).config
        encoding = "bgr8" if r.rect_left.ndim == 3 else "mono8"
        self._put("image", stamp, m.image(header, r.rect_left, encoding))
        self._put("left_info", stamp, m.camera_info(header, rect))
        self._put("right_info", stamp, m.camera_info(header, rect, right=True))
        self._put("disparity", stamp, m.disparity(header, r, rect, min_disparity=config.min_disparity,
                                                  num_disparities=config.num_disparities))
        self._put("depth", stamp, m.depth(header, r, self.options.depth_encoding))
        self._put("depth_info", stamp, m.camera_info(header, rect))
        if self.options.points:
            self._put("points", stamp, m.points(header, r))
        self.frames += 1

    def _close(self) -> None:
        writer, self._writer = self._writer, None
        if writer is not None:
            try:
                writer.close()
            except OSError as exc:
                raise S2RError(f"cannot write: {exc.strerror}; nothing was written", path=self.out,
                               hint="free some space or choose a writable location") from None

    def publish(self) -> list[Path]:
        self._check_frames()
        self._close()
        if self.ros1:
            with OutputBatch(force=self.force) as batch:
                batch.add_file(self.out, self._bag_path)
                return batch.publish()
        created = not self.out.exists()
        prepare_output_dir(self.out, force=self.force)
        try:
            with OutputBatch(force=self.force, root=self.out) as batch:
                for name in sorted(p.name for p in self._bag_path.iterdir()):  # metadata.yaml and NAME.mcap
                    batch.add_file(self.out / name, self._bag_path / name)
                return batch.publish()
        except BaseException:
            if created:
                with contextlib.suppress(OSError):
                    self.out.rmdir()  # this run's folder, empty again after the batch was undone
            raise

    def discard(self) -> None:
        try:
            self._close()
        except S2RError:
            pass
        finally:
            shutil.rmtree(self._tmp, ignore_errors=True)
