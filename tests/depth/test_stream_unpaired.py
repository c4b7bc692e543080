"""``s2r depth`` says which input images it skipped for want of a partner (a warning naming the first few, the
count in the summary and in --json), and frames.csv holds only the pairs; bags' unmatched messages likewise."""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.recordings import open_recording, skipped_inputs
from tests.depth.stream_inputs import known_frames, known_rig, write_folder, write_profile


@pytest.fixture(scope="module")
def rig_folder(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, list[str]]:
    rig, profile = known_rig()
    root = tmp_path_factory.mktemp("unpaired")
    names = write_folder(known_frames(rig, distances_m=(0.9, 1.3)), root / "rec")
    for k in range(7):  # seven left images whose right partner is missing
        shutil.copy(root / "rec" / "left" / f"{names[0]}.png", root / "rec" / "left" / f"shot_{10 + k:02d}.png")
    return write_profile(profile, root / "profile.yaml"), root / "rec", names


def test_unpaired_images_are_counted_and_named(rig_folder: tuple[Path, Path, list[str]], tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    profile, rec, names = rig_folder
    out = tmp_path / "out"
    assert main(["depth", str(profile), str(rec), "-o", str(out), "--json"]) == 0
    captured = capsys.readouterr()
    summary = json.loads(captured.out)
    assert summary["frames"] == 2 and summary["skipped_unpaired"] == 7
    assert [Path(p).name for p in summary["skipped_first"]] == [f"shot_{10 + k:02d}.png" for k in range(5)]
    (warning,) = [line for line in captured.err.splitlines() if "no partner" in line]
    assert "7 input image(s) had no partner and were skipped" in warning
    assert "shot_10.png" in warning and "shot_14.png" in warning and "and 2 more" in warning
    rows = list(csv.DictReader((out / "frames.csv").open()))
    assert [r["name"] for r in rows] == names
    assert main(["depth", str(profile), str(rec), "-o", str(tmp_path / "o3")]) == 0
    assert "7 unpaired input image(s) skipped" in capsys.readouterr().out


def test_bag_messages_without_a_partner_are_listed(tmp_path: Path) -> None:
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    from tests.recordings.helpers import image_msg

    ts = get_typestore(Stores.ROS1_NOETIC)
    image = np.zeros((48, 64), np.uint8)
    left = [1_000_000_000, 1_100_000_000, 1_200_000_000, 1_300_000_000]  # the last has no right partner
    right = [1_002_000_000, 1_150_000_000, 1_102_000_000, 1_202_000_000]  # 1.15 s has no left partner
    bag = tmp_path / "b.bag"
    with Writer(bag) as writer:
        conns = {t: writer.add_connection(t, "sensor_msgs/msg/Image", typestore=ts) for t in ("/l", "/r")}
        for topic, stamps in (("/l", left), ("/r", right)):
            for t in stamps:
                writer.write(conns[topic], t, ts.serialize_ros1(image_msg(ts, image, t, ros1=True),
                                                                 "sensor_msgs/msg/Image"))
    source = open_recording(bag=bag, left_topic="/l", right_topic="/r")
    assert [f.stamp_ns for f in source.frames()] == left[:3]
    assert skipped_inputs(source) == ["/r @ 1150000000 ns", "/l @ 1300000000 ns"]
