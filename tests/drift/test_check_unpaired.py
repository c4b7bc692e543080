"""``s2r check --json`` counts the images it skipped for want of a partner, with the keys ``s2r depth``'s summary
uses (``skipped_unpaired``, ``skipped_first``), and so does each robot's row of ``s2r fleet check`` (its check.json
and summary.json): a script sees that fewer frames were checked than the folder seems to hold."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.drift.check import CheckSettings
from s2r.drift.fleet import load_fleet, run_robot
from tests.depth.stream_inputs import known_frames, known_rig, write_folder, write_profile


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    rig, profile = known_rig()
    root = tmp_path_factory.mktemp("unpaired")
    write_folder(known_frames(rig, distances_m=(1.0, 1.3)), root / "paired")
    shutil.copytree(root / "paired", root / "unpaired")
    for name in ("shot_07.png", "shot_08.png"):  # left images without a right partner
        shutil.copy(root / "unpaired" / "left" / "shot_00.png", root / "unpaired" / "left" / name)
    return {"profile": write_profile(profile, root / "rig.yaml"), "root": root}


@pytest.mark.parametrize(("recording", "count"), [("unpaired", 2), ("paired", 0)])
def test_check_json_counts_the_unpaired_images(inputs: dict[str, Path], recording: str, count: int,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["check", str(inputs["profile"]), str(inputs["root"] / recording), "--json"]) in (0, 1)
    data = json.loads(capsys.readouterr().out)
    assert data["skipped_unpaired"] == count
    assert [Path(p).name for p in data["skipped_first"]] == ["shot_07.png", "shot_08.png"][:count]


def test_a_fleet_robot_row_counts_them_too(inputs: dict[str, Path], tmp_path: Path) -> None:
    fleet = tmp_path / "fleet.yaml"
    fleet.write_text(json.dumps({"robots": [{"name": "r1", "profile": str(inputs["profile"]),
                                             "recording": str(inputs["root"] / "unpaired")}]}))
    row = run_robot(load_fleet(fleet, settings=CheckSettings())[0])
    assert row["verdict"] != "failed", row["reasons"]
    assert row["skipped_unpaired"] == 2
    assert [Path(p).name for p in row["skipped_first"]] == ["shot_07.png", "shot_08.png"]
