"""Input that is rectified already (its frame named so, as s2r labels its own outputs): the outputs keep that
frame's name (never ``..._rect_rect_...``) and ``/tf_static`` holds no transform of a frame into itself."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import pytest

from s2r.cli import main
from s2r.depth.pipeline import StereoPipeline
from s2r.depth.prerectified import rectified_profile
from s2r.depth.stream import rectified_frame_id
from tests.depth.stream_inputs import (
    LEFT_TOPIC,
    RECT_FRAME_ID,
    RIGHT_TOPIC,
    KnownFrame,
    known_frames,
    known_rig,
    write_profile,
    write_ros2_bag,
)


@pytest.mark.parametrize(("optical", "rectified"), [
    ("cam_optical_frame", "cam_rect_optical_frame"), ("cam_optical", "cam_rect_optical"), ("cam", "cam_rect"),
    ("cam_rect_optical_frame", "cam_rect_optical_frame"), ("cam_rect_optical", "cam_rect_optical"),
    ("cam_rect", "cam_rect"), ("rectifier_optical_frame", "rectifier_rect_optical_frame"),
    ("cam_rectified", "cam_rectified_rect")])
def test_rectified_frame_id_is_added_once(optical: str, rectified: str) -> None:
    assert rectified_frame_id(optical) == rectified


def _tf_pairs(bag: Path) -> list[tuple[str, str]]:
    """(parent, child) of every transform on /tf_static, read by rosbags' AnyReader."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    pairs: list[tuple[str, str]] = []
    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        frames: set[str] = set()
        for conn, _, raw in reader.messages():
            msg: Any = reader.deserialize(raw, conn.msgtype)
            if conn.topic == "/tf_static":
                pairs += [(t.header.frame_id, t.child_frame_id) for t in msg.transforms]
            elif hasattr(msg, "header"):
                frames.add(msg.header.frame_id)
    assert frames == {RECT_FRAME_ID}, frames  # every message of the data
    return pairs


@pytest.fixture(scope="module")
def rectified(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The known pairs rectified by s2r's pipeline, in a ROS 2 bag labelled with the rectified frame s2r names its
    outputs by, with the profile of the rectified cameras (no frame_id: the recording's is used) and the raw one
    without its frame_id."""
    rig, profile = known_rig()
    pipe = StereoPipeline(profile)
    rect = pipe.rectification
    frames = []
    for f in known_frames(rig, (0.9, 1.3)):
        result = pipe.compute(f.left, f.right)
        frames.append(KnownFrame(result.rect_left, result.rect_right, f.normal, f.offset_m))
    root = tmp_path_factory.mktemp("rectified")
    write_ros2_bag(frames, root / "in_bag", frame_id=RECT_FRAME_ID)
    given = rectified_profile(rect.image_size, f_px=rect.fx_px, baseline_m=rect.baseline_m,
                              cx_px=float(rect.P1[0, 2]), cy_px=float(rect.P1[1, 2]), name="raycast_rectified")
    raw = profile.model_copy(update={"left": profile.left.model_copy(update={"frame_id": ""}),
                                     "right": profile.right.model_copy(update={"frame_id": ""})})
    return {"bag": root / "in_bag", "rectified": write_profile(given, root / "rectified.yaml"),
            "raw": write_profile(raw, root / "raw.yaml")}


def _depth(profile: Path, bag: Path, out: Path, *target: str) -> None:
    assert main(["depth", str(profile), "--bag", str(bag), "--left-topic", LEFT_TOPIC, "--right-topic", RIGHT_TOPIC,
                 "-o", str(out), *target]) == 0


def test_rectified_input_keeps_its_frame(rectified: dict[str, Path], tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    _depth(rectified["rectified"], rectified["bag"], tmp_path / "bag", "--to", "ros2")
    # the right camera placed in the (rectified) left frame; no rectified frame in itself
    assert _tf_pairs(tmp_path / "bag") == [(RECT_FRAME_ID, RECT_FRAME_ID.replace("left", "right"))]
    _depth(rectified["rectified"], rectified["bag"], tmp_path / "files")
    rows = list(csv.DictReader((tmp_path / "files" / "frames.csv").open()))
    assert {r["frame_id"] for r in rows} == {RECT_FRAME_ID} and len(rows) == 2
    assert "rectified already" not in capsys.readouterr().err  # R1 = I: nothing turned


def test_rectifying_rectified_input_again_is_warned(rectified: dict[str, Path], tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """The raw profile on rectified input turns it by R1 once more: said once, the name still kept."""
    _depth(rectified["raw"], rectified["bag"], tmp_path / "files")
    err = capsys.readouterr().err
    assert err.count("rectified already") == 1 and RECT_FRAME_ID in err, err
    rows = list(csv.DictReader((tmp_path / "files" / "frames.csv").open()))
    assert {r["frame_id"] for r in rows} == {RECT_FRAME_ID}
