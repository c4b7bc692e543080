"""ROS 2 bags carry a metadata version that Humble's and Jazzy's ``ros2 bag`` both read (ros2/rosbag2#2013).

Read back by rosbags' AnyReader and by the ``mcap`` package (no s2r code).
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from s2r.cli import main
from tests.depth.stream_inputs import LEFT_TOPIC, RIGHT_TOPIC, known_frames, known_rig, write_profile, write_ros2_bag


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    rig, profile = known_rig()
    root = tmp_path_factory.mktemp("bagversion")
    write_ros2_bag(known_frames(rig, distances_m=(0.9, 1.3)), root / "in_bag")
    return write_profile(profile, root / "profile.yaml"), root / "in_bag"


def test_ros2_bag_metadata_is_version_8_which_humble_and_jazzy_read(inputs: tuple[Path, Path], tmp_path: Path) -> None:
    """Humble's rosbag2 reads ``offered_qos_profiles`` as a YAML string of integer policies (version <= 8);
    Jazzy's version 9 makes it a list, which Humble refuses (ros2/rosbag2#2013)."""
    from mcap.reader import make_reader
    from rosbags.highlevel import AnyReader

    bag = tmp_path / "b"
    assert main(["-q", "depth", str(inputs[0]), "--bag", str(inputs[1]), "--left-topic",
                 LEFT_TOPIC, "--right-topic", RIGHT_TOPIC, "-o", str(bag), "--to", "ros2"]) == 0
    info = yaml.safe_load((bag / "metadata.yaml").read_text(encoding="utf-8"))["rosbag2_bagfile_information"]
    assert info["version"] == 8 and info["storage_identifier"] == "mcap"
    for topic in info["topics_with_message_count"]:
        qos = topic["topic_metadata"]["offered_qos_profiles"]
        assert isinstance(qos, str)  # Humble: a string holding YAML, not a YAML list
        for profile in yaml.safe_load(qos) or []:
            assert all(isinstance(profile[k], int) for k in ("history", "reliability", "durability", "liveliness"))
        if topic["topic_metadata"]["name"] == "/tf_static":
            (latched,) = yaml.safe_load(qos)
            assert latched["durability"] == 1  # RMW_QOS_POLICY_DURABILITY_TRANSIENT_LOCAL
    with (bag / "b.mcap").open("rb") as handle:  # the copy inside the mcap file says the same
        records = {m.name: m.metadata for m in make_reader(handle).iter_metadata()}
    assert yaml.safe_load(records["rosbag2"]["serialized_metadata"])["version"] == 8
    with AnyReader([bag]) as reader:
        assert reader.message_count == info["message_count"] > 0
