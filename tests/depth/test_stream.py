"""Depth on streams: ``s2r depth PROFILE <recording> -o OUT --to files|ros2|ros1`` and ``StereoPipeline.stream``.

Inputs come from tests/raycast.py (an independent ray caster) as PNG folders and as a ROS 2 bag written by rosbags.
Every output bag is read by two readers that share no code with s2r's writer: rosbags' AnyReader and the ``mcap`` +
``mcap-ros2-support`` packages (ROS 2); ROS 1 bags by rosbags here and by Debian's rosbag in tests/ros.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from s2r.cli import main
from s2r.depth.pipeline import StereoPipeline
from s2r.recordings import StereoFrame
from tests.depth.stream_inputs import (
    FRAME_ID,
    LEFT_TOPIC,
    RECT_FRAME_ID,
    RIGHT_TOPIC,
    STAMPS_NS,
    KnownFrame,
    known_frames,
    known_rig,
    truth_depth,
    write_folder,
    write_profile,
    write_ros2_bag,
)

TOPICS = {"/stereo/left/image_rect", "/stereo/left/camera_info", "/stereo/right/camera_info", "/stereo/disparity",
          "/stereo/depth/image_rect", "/stereo/depth/camera_info", "/tf_static"}


@pytest.fixture(scope="module")
def known(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    rig, profile = known_rig()
    frames = known_frames(rig)
    root = tmp_path_factory.mktemp("known")
    names = write_folder(frames, root / "rec")
    write_ros2_bag(frames, root / "in_bag")
    return {"profile": profile, "path": write_profile(profile, root / "profile.yaml"), "frames": frames,
            "names": names, "root": root}


def _bag_messages(path: Path) -> dict[str, list[tuple[int, Any]]]:
    """topic -> [(log time ns, message)] through rosbags' AnyReader."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    out: dict[str, list[tuple[int, Any]]] = {}
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        for conn, stamp, raw in reader.messages():
            out.setdefault(conn.topic, []).append((stamp, reader.deserialize(raw, conn.msgtype)))
    return out


def _mcap_messages(folder: Path) -> dict[str, list[Any]]:
    """topic -> [decoded message] through the mcap packages (the ROS 2 bag's .mcap file)."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    (file,) = folder.glob("*.mcap")
    out: dict[str, list[Any]] = {}
    with file.open("rb") as handle:
        for _, channel, _, decoded in make_reader(handle, decoder_factories=[DecoderFactory()]
                                                  ).iter_decoded_messages():
            out.setdefault(channel.topic, []).append(decoded)
    return out


def _image(msg: Any, dtype: Any) -> np.ndarray:
    return np.frombuffer(bytes(msg.data), dtype=dtype).reshape(msg.height, msg.width)


def test_files_named_after_the_input_with_an_index_and_known_depth(known: dict[str, Any], tmp_path: Path) -> None:
    out = tmp_path / "files"
    assert main(["-q", "depth", str(known["path"]), str(known["root"] / "rec"), "-o", str(out), "--pcd"]) == 0
    rows = list(csv.DictReader((out / "frames.csv").open()))
    assert [r["name"] for r in rows] == known["names"] and [r["index"] for r in rows] == ["0", "1", "2"]
    assert {r["stamp_source"] for r in rows} == {"synthesized"} and {r["frame_id"] for r in rows} == {RECT_FRAME_ID}
    stamps = [int(r["stamp_ns"]) for r in rows]
    assert stamps == sorted(stamps) and len(set(stamps)) == 3
    pipe = StereoPipeline(known["profile"])
    rect = pipe.rectification
    for row, frame in zip(rows, known["frames"], strict=True):
        assert row["source"].endswith(f"{row['name']}.png")
        depth = np.load(out / row["depth_npy"])
        assert (out / row["depth_png"]).is_file() and (out / row["points_pcd"]).is_file()
        truth = truth_depth(frame, rect.P1, rect.R1, depth.shape)
        valid = np.isfinite(depth)
        assert valid.mean() > 0.6
        # against the matcher's theory: dz = Z^2 dd / (f B), SGBM's sub-pixel bias up to 0.2 px (REFERENCE.md)
        dd = (depth[valid] - truth[valid]) * rect.fx_px * rect.baseline_m / truth[valid] ** 2
        assert float(np.median(np.abs(dd))) < 0.2
        assert abs(float(np.median(dd))) < 0.15


def test_pcd_holds_the_ply_points(known: dict[str, Any], tmp_path: Path) -> None:
    out = tmp_path / "pts"
    assert main(["-q", "depth", str(known["path"]), str(known["root"] / "rec"), "-o", str(out), "--ply", "--pcd",
                 "--max-frames", "1"]) == 0
    name = known["names"][0]
    pcd = (out / "points" / f"{name}.pcd").read_bytes()
    header, _, body = pcd.partition(b"DATA binary\n")
    n = int(header.split(b"POINTS ")[1].split(b"\n")[0])
    rows = np.frombuffer(body, dtype=[("xyz", "<f4", (3,)), ("rgb", "<u4")])
    ply = (out / "points" / f"{name}.ply").read_bytes()
    ply_rows = np.frombuffer(ply.partition(b"end_header\n")[2], dtype=[("xyz", "<f4", (3,)), ("rgb", "u1", (3,))])
    assert len(rows) == n == len(ply_rows) > 1000
    np.testing.assert_array_equal(rows["xyz"], ply_rows["xyz"])
    grey = ply_rows["rgb"][:, 0].astype(np.uint32)
    np.testing.assert_array_equal(rows["rgb"], (grey << 16) | (grey << 8) | grey)


@pytest.mark.parametrize("target", ["ros2", "ros1"])
def test_bag_depth_equals_files_depth_bit_for_bit(known: dict[str, Any], tmp_path: Path, target: str) -> None:
    files, bag = tmp_path / "files", tmp_path / ("out_bag" if target == "ros2" else "out.bag")
    assert main(["-q", "depth", str(known["path"]), str(known["root"] / "rec"), "-o", str(files)]) == 0
    assert main(["-q", "depth", str(known["path"]), "--bag", str(known["root"] / "in_bag"), "--left-topic",
                 LEFT_TOPIC, "--right-topic", RIGHT_TOPIC, "-o", str(bag), "--to", target, "--points"]) == 0
    msgs = _bag_messages(bag)
    assert set(msgs) == TOPICS | {"/stereo/points2"}
    depths = [m for _, m in msgs["/stereo/depth/image_rect"]]
    assert [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for m in depths] == list(STAMPS_NS)
    assert [t for t, _ in msgs["/stereo/disparity"]] == list(STAMPS_NS)
    assert {m.header.frame_id for topic, ms in msgs.items() if topic != "/tf_static" for _, m in ms} == {RECT_FRAME_ID}
    rect = StereoPipeline(known["profile"]).rectification
    for name, depth_msg, (_, disp_msg) in zip(known["names"], depths, msgs["/stereo/disparity"], strict=True):
        assert depth_msg.encoding == "32FC1"
        from_bag = _image(depth_msg, np.float32)
        from_files = np.load(files / "depth" / f"{name}.npy")
        assert from_bag.tobytes() == from_files.tobytes()  # bit for bit, NaNs included
        d = _image(disp_msg.image, np.float32)
        valid = d >= disp_msg.min_disparity
        np.testing.assert_array_equal(valid, np.isfinite(from_files))
        f, baseline = disp_msg.f, (disp_msg.T if target == "ros1" else disp_msg.t)
        np.testing.assert_allclose(f * baseline / d[valid], from_files[valid], rtol=1e-6)
        assert f == pytest.approx(rect.fx_px) and baseline == pytest.approx(rect.baseline_m)
    right_info = msgs["/stereo/right/camera_info"][0][1]
    P = np.asarray(right_info.P if target == "ros1" else right_info.p).reshape(3, 4)
    assert P[0, 3] == pytest.approx(-rect.fx_px * rect.baseline_m)
    (tf,) = [m for _, m in msgs["/tf_static"]]
    transform, to_rect = tf.transforms
    assert transform.header.frame_id == FRAME_ID and transform.child_frame_id == "raycast_right_optical"
    t = transform.transform.translation
    np.testing.assert_allclose([t.x, t.y, t.z], -known["profile"].R.T @ known["profile"].T, atol=1e-12)
    # the rectified frame the data are labelled with, placed in the optical one: X_left = R1^T X_rect
    assert (to_rect.header.frame_id, to_rect.child_frame_id) == (FRAME_ID, RECT_FRAME_ID)
    q, t = to_rect.transform.rotation, to_rect.transform.translation
    np.testing.assert_allclose(Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix(), rect.R1.T, atol=1e-12)
    assert (t.x, t.y, t.z) == (0.0, 0.0, 0.0)
    # a point of the cloud (rectified frame) taken to the optical frame through tf lies on the input's ray there
    cloud0 = msgs["/stereo/points2"][0][1]
    xyz0 = np.frombuffer(bytes(cloud0.data), np.float32).reshape(cloud0.height, cloud0.width, 4)[..., :3]
    v, u = np.argwhere(np.isfinite(xyz0[..., 2]))[len(np.argwhere(np.isfinite(xyz0[..., 2]))) // 2]
    in_optical = rect.R1.T @ xyz0[v, u].astype(np.float64)
    truth = known["frames"][0]
    assert abs(float(truth.normal @ in_optical) - truth.offset_m) < 0.01  # on the plane, in the left optical frame
    assert abs(float(truth.normal @ xyz0[v, u]) - truth.offset_m) > abs(float(truth.normal @ in_optical)
                                                                        - truth.offset_m)
    cloud = msgs["/stereo/points2"][-1][1]  # the last frame, as valid and from_files
    xyz = np.frombuffer(bytes(cloud.data), np.float32).reshape(cloud.height, cloud.width, 4)[..., :3]
    np.testing.assert_allclose(xyz[..., 2][valid], from_files[valid], rtol=1e-5)


def test_ros2_bag_read_by_the_mcap_packages(known: dict[str, Any], tmp_path: Path) -> None:
    bag = tmp_path / "b"
    assert main(["-q", "depth", str(known["path"]), "--bag", str(known["root"] / "in_bag"), "--left-topic",
                 LEFT_TOPIC, "--right-topic", RIGHT_TOPIC, "-o", str(bag), "--to", "ros2", "--depth-encoding",
                 "16UC1", "--namespace", "/d435"]) == 0
    via_mcap = _mcap_messages(bag)
    assert set(via_mcap) == {t.replace("/stereo", "/d435") for t in TOPICS}
    via_rosbags = _bag_messages(bag)
    for topic, decoded in via_mcap.items():
        assert len(decoded) == len(via_rosbags[topic])
    for a, (_, b) in zip(via_mcap["/d435/depth/image_rect"], via_rosbags["/d435/depth/image_rect"], strict=True):
        assert a.encoding == b.encoding == "16UC1"
        assert bytes(a.data) == bytes(b.data)
        assert (a.header.stamp.sec, a.header.stamp.nanosec, a.header.frame_id) == (
            b.header.stamp.sec, b.header.stamp.nanosec, RECT_FRAME_ID)
    pipe = StereoPipeline(known["profile"])
    first = next(iter(pipe.stream([_frame(known["frames"][0])])))
    mm = _image(via_mcap["/d435/depth/image_rect"][0], np.uint16)
    expected = np.where(first.result.valid, np.clip(np.rint(first.result.depth * 1000), 1, 65535), 0)
    min_m, max_m = known["profile"].matcher.min_depth_m, known["profile"].matcher.max_depth_m
    in_range = (first.result.depth >= min_m) & (first.result.depth <= max_m)
    np.testing.assert_array_equal(mm[in_range & first.result.valid], expected[in_range & first.result.valid])


def _frame(frame: KnownFrame, index: int = 0, stamp: int | None = None) -> StereoFrame:
    return StereoFrame(index=index, name=f"f{index}", stamp_ns=stamp, frame_id="", left=frame.left, right=frame.right,
                       source=f"test frame {index}")


def test_python_api_stream_in_order_with_names_stamps_and_frame_id(known: dict[str, Any]) -> None:
    frames = [_frame(f, k, STAMPS_NS[k]) for k, f in enumerate(known["frames"])] * 2
    pipe = StereoPipeline(known["profile"], preset="fast")
    got = list(pipe.stream(frames, workers=2))
    assert [g.stamp_ns for g in got] == list(STAMPS_NS) * 2 and not any(g.stamp_synthesized for g in got)
    assert {g.frame_id for g in got} == {FRAME_ID}
    for g, f in zip(got, frames, strict=True):
        plain = pipe.compute(f.left, f.right)
        assert g.result.depth.tobytes() == plain.depth.tobytes()
    profile = known["profile"].model_copy(update={"left": known["profile"].left.model_copy(update={"frame_id": ""})})
    taken = next(iter(StereoPipeline(profile).stream([_frame(known["frames"][0]).__class__(
        index=0, name="a", stamp_ns=None, frame_id="from_input", left=known["frames"][0].left,
        right=known["frames"][0].right, source="x")])))
    assert taken.frame_id == "from_input" and taken.stamp_synthesized


def test_stopping_early_stops_the_stream(known: dict[str, Any]) -> None:
    read: list[int] = []

    def frames() -> Any:
        for k in range(1000):
            read.append(k)
            yield _frame(known["frames"][k % 3], k)

    for k, _ in enumerate(StereoPipeline(known["profile"], preset="fast").stream(frames(), workers=2)):
        if k == 2:
            break
    assert len(read) < 20  # bounded read-ahead, not the whole recording


def test_readme_stream_script_runs(known: dict[str, Any], tmp_path: Path) -> None:
    import re
    import subprocess
    import sys

    text = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    section = text[text.index("Every frame of a recording, with the profile chosen by name"):]
    block = re.search(r"```python\n(.*?)```", section, re.S)
    assert block
    script = tmp_path / "stream_demo.py"
    script.write_text(block.group(1))
    done = subprocess.run([sys.executable, str(script), str(known["path"]), str(known["root"] / "rec")],
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    lines = [line.split() for line in done.stdout.splitlines()]
    assert [line[0] for line in lines] == known["names"] and {line[2] for line in lines} == {FRAME_ID}
    assert [float(line[3]) for line in lines] == pytest.approx([0.84, 1.19, 1.62], abs=0.03)  # the planes' medians
    via_path = [f.name for f in StereoPipeline(known["path"]).stream(known["root"] / "rec")]
    assert via_path == known["names"]


def test_the_known_depth_generator_shares_no_code_with_s2r() -> None:
    import ast

    tree = ast.parse((Path(__file__).resolve().parents[1] / "raycast.py").read_text())
    imported = {alias.name.split(".")[0] for node in ast.walk(tree) if isinstance(node, ast.Import)
                for alias in node.names}
    imported |= {node.module.split(".")[0] for node in ast.walk(tree)
                 if isinstance(node, ast.ImportFrom) and node.module}
    assert imported <= {"__future__", "math", "dataclasses", "pathlib", "cv2", "numpy"}, imported
