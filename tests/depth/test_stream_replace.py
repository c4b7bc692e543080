"""``--force`` replaces a multi-file output whole (never merges with an old one), keeps the old one when the run
fails; a failed calibration leaves no corner cache."""

from __future__ import annotations

import csv
import os
from pathlib import Path
from typing import Any

import pytest

from s2r.cli import main
from s2r.errors import OutputExistsError
from s2r.fileio import TEMP_PREFIX, prepare_output_dir, removing_new_folders_on_failure
from tests.depth.stream_inputs import (
    known_frames,
    known_rig,
    write_folder,
    write_profile,
)


@pytest.fixture(scope="module")
def known(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    rig, profile = known_rig()
    frames = known_frames(rig, distances_m=(0.9, 1.3))
    root = tmp_path_factory.mktemp("replace")
    names = write_folder(frames, root / "rec")
    return {"profile": write_profile(profile, root / "profile.yaml"), "names": names, "root": root}


def _tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _no_temporaries(parent: Path) -> None:
    assert not [p.name for p in parent.iterdir() if p.name.startswith(TEMP_PREFIX)]


def test_force_replaces_a_files_output_whole(known: dict[str, Any], tmp_path: Path) -> None:
    out = tmp_path / "out"
    rec = str(known["root"] / "rec")
    assert main(["-q", "depth", str(known["profile"]), rec, "-o", str(out)]) == 0
    (out / "depth" / "stale_frame.png").write_bytes(b"old")
    (out / "old.mcap").write_bytes(b"old bag")
    assert main(["-q", "depth", str(known["profile"]), rec, "-o", str(out), "--max-frames", "1", "--force"]) == 0
    rows = list(csv.DictReader((out / "frames.csv").open()))
    assert [r["name"] for r in rows] == known["names"][:1]
    assert sorted(p.name for p in (out / "depth").iterdir()) == [f"{known['names'][0]}.npy",
                                                                  f"{known['names'][0]}.png"]
    assert not (out / "old.mcap").exists()
    _no_temporaries(tmp_path)


def test_force_replaces_a_ros2_bag_folder_whole(known: dict[str, Any], tmp_path: Path) -> None:
    out = tmp_path / "bag"
    out.mkdir()
    (out / "old.mcap").write_bytes(b"an older bag's file")
    (out / "metadata.yaml").write_text("old", encoding="utf-8")
    assert main(["-q", "depth", str(known["profile"]), str(known["root"] / "rec"), "-o", str(out), "--to", "ros2",
                 "--force"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["bag.mcap", "metadata.yaml"]
    _no_temporaries(tmp_path)


def test_failed_forced_run_keeps_the_old_output_intact(known: dict[str, Any], tmp_path: Path) -> None:
    out = tmp_path / "out"
    rec = known["root"] / "rec"
    assert main(["-q", "depth", str(known["profile"]), str(rec), "-o", str(out)]) == 0
    before = _tree(out)
    broken = tmp_path / "broken"
    broken.mkdir()
    for p in rec.rglob("*.png"):  # the same layout, the second left image cut short
        dst = broken / p.relative_to(rec)
        dst.parent.mkdir(parents=True, exist_ok=True)
        data = p.read_bytes()
        dst.write_bytes(data[:200] if p.name == known["names"][1] + ".png" and "left" in str(p.parent) else data)
    assert main(["-q", "depth", str(known["profile"]), str(broken), "-o", str(out), "--force"]) == 2
    assert _tree(out) == before
    _no_temporaries(tmp_path)


def test_replacement_is_undone_on_failure_and_finished_on_success(tmp_path: Path) -> None:
    out = tmp_path / "report"
    out.mkdir()
    (out / "old.html").write_text("old", encoding="utf-8")
    with pytest.raises(RuntimeError), removing_new_folders_on_failure():
        prepare_output_dir(out, force=True)
        assert list(out.iterdir()) == []  # a new, empty folder; the old one is aside until the end
        (out / "new.html").write_text("new", encoding="utf-8")
        raise RuntimeError("the run failed")
    assert _tree(out) == {"old.html": b"old"}
    with removing_new_folders_on_failure():
        prepare_output_dir(out, force=True)
        (out / "new.html").write_text("new", encoding="utf-8")
    assert _tree(out) == {"new.html": b"new"}
    _no_temporaries(tmp_path)
    # a folder of the user's that only receives named files is not replaced
    prepare_output_dir(out, force=True, replace=False)
    assert _tree(out) == {"new.html": b"new"}


def test_force_never_replaces_the_working_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "precious.txt").write_text("keep", encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    with pytest.raises(OutputExistsError, match="working folder"), removing_new_folders_on_failure():
        prepare_output_dir(".", force=True)
    with pytest.raises(OutputExistsError, match="working folder"), removing_new_folders_on_failure():
        prepare_output_dir(tmp_path.parent, force=True)
    assert (tmp_path / "precious.txt").read_text(encoding="utf-8") == "keep"


def test_failed_calibration_leaves_no_corner_cache(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from s2r.calib.solve.synth import write_stereo_set
    from tests.calib.conftest import distorted_truth

    write_stereo_set(distorted_truth(), tmp_path / "set", views=3, seed=7)  # too few views: refused after detection
    before = sorted(os.listdir(tmp_path))
    out = tmp_path / "rig.yaml"
    assert main(["calibrate", "--pattern", "9x6", "--square", "0.025", str(tmp_path / "set"), "-o", str(out),
                 "--jobs", "1"]) == 2
    assert "at least" in capsys.readouterr().err
    assert sorted(os.listdir(tmp_path)) == before  # no rig.yaml, no rig.yaml.corners/


def test_force_never_replaces_a_folder_holding_an_input(known: dict[str, Any], tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]) -> None:
    data = tmp_path / "data"
    for side in ("left", "right"):
        (data / side).mkdir(parents=True)
        for p in (known["root"] / "rec" / side).iterdir():
            (data / side / p.name).write_bytes(p.read_bytes())
    before = _tree(data)
    for inputs in (["--left-dir", str(data / "left"), "--right-dir", str(data / "right")],
                   ["--left", str(data / "left" / "*.png"), "--right", str(data / "right" / "*.png")],
                   [str(data / "left" / f"{known['names'][0]}.png"), str(data / "right" / f"{known['names'][0]}.png")]):
        assert main(["depth", str(known["profile"]), *inputs, "-o", str(data), "--force"]) == 2
        assert "an input of this command: --force would replace the folder whole" in capsys.readouterr().err
        assert _tree(data) == before
    _no_temporaries(tmp_path)


def test_force_replaces_a_single_pair_output_whole(known: dict[str, Any], tmp_path: Path) -> None:
    out = tmp_path / "pair"
    left, right = (known["root"] / "rec" / side / f"{known['names'][0]}.png" for side in ("left", "right"))
    assert main(["-q", "depth", str(known["profile"]), str(left), str(right), "-o", str(out), "--ply"]) == 0
    assert (out / "points.ply").is_file()
    assert main(["-q", "depth", str(known["profile"]), str(left), str(right), "-o", str(out), "--force"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["camera_info.yaml", "depth.png", "depth_color.png",
                                                     "disparity.npy"]
