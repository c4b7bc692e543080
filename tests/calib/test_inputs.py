"""Finding and pairing calibration images: layouts, numbers in names, globs, mistakes."""

from __future__ import annotations

from pathlib import Path

import pytest

from s2r.calib.detect.inputs import find_mono_images, find_stereo_pairs, pair_by_number
from s2r.errors import CalibrationError


def _touch(folder: Path, *names: str) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    for name in names:
        (folder / name).write_bytes(b"")


def test_subfolders_pair_by_number_and_name_the_unpaired(tmp_path: Path) -> None:
    _touch(tmp_path / "left", "00.png", "01.png", "02.png", "notes.txt")
    _touch(tmp_path / "right", "00.png", "01.png", "03.png")
    pairs = find_stereo_pairs(tmp_path)
    assert [p.name for p in pairs.left] == ["00.png", "01.png"] and pairs.names == ("00", "01")
    assert [f"{p.parent.name}/{p.name}" for p in pairs.unpaired] == ["left/02.png", "right/03.png"]


def test_prefixed_files_pair_by_number_not_by_position(tmp_path: Path) -> None:
    # the OpenCV sample layout: left01.jpg ... left14.jpg, no pair 10, one unpadded right name
    _touch(tmp_path, "left01.jpg", "left09.jpg", "left11.jpg", "right01.jpg", "right9.jpg", "right11.jpg",
           "right12.jpg")
    pairs = find_stereo_pairs(tmp_path)
    assert [(a.name, b.name) for a, b in zip(pairs.left, pairs.right, strict=True)] == [
        ("left01.jpg", "right01.jpg"), ("left09.jpg", "right9.jpg"), ("left11.jpg", "right11.jpg")]
    assert [p.name for p in pairs.unpaired] == ["right12.jpg"]


def test_globs_without_numbers_pair_in_sorted_order(tmp_path: Path) -> None:
    _touch(tmp_path / "a", "first.png", "second.png")
    _touch(tmp_path / "b", "one.png", "two.png")
    pairs = find_stereo_pairs(left_glob=str(tmp_path / "a" / "*.png"), right_glob=str(tmp_path / "b" / "*.png"))
    assert [p.name for p in pairs.left] == ["first.png", "second.png"]
    assert [p.name for p in pairs.right] == ["one.png", "two.png"]


def test_duplicate_numbers_are_refused(tmp_path: Path) -> None:
    _touch(tmp_path, "a_01.png", "b_1.png", "r_01.png")
    with pytest.raises(CalibrationError, match="share one pairing number"):
        pair_by_number([tmp_path / "a_01.png", tmp_path / "b_1.png"], [tmp_path / "r_01.png"])


def test_folder_without_images_says_what_layout_is_expected(tmp_path: Path) -> None:
    _touch(tmp_path, "readme.txt")
    with pytest.raises(CalibrationError, match=r"leftNN\.png / rightNN\.png"):
        find_stereo_pairs(tmp_path)
    with pytest.raises(CalibrationError, match="--left and --right must be given together"):
        find_stereo_pairs(left_glob="*.png")


def test_mono_prefers_left_images(tmp_path: Path) -> None:
    _touch(tmp_path, "left01.png", "left02.png", "right01.png")
    assert [p.name for p in find_mono_images(tmp_path)] == ["left01.png", "left02.png"]
    _touch(tmp_path / "cam", "img1.png", "img2.png")
    assert [p.name for p in find_mono_images(tmp_path / "cam")] == ["img1.png", "img2.png"]


@pytest.mark.parametrize(("left", "right"), [("cam0/data", "cam1/data"), ("cam0", "cam1"), ("Left", "Right"),
                                             ("image_0", "image_1")])
def test_camera_subfolders_of_kalibr_euroc_and_kitti_layouts(tmp_path: Path, left: str, right: str) -> None:
    # EuRoC / Kalibr extraction: camN/data/<stamp ns>.png; KITTI: image_0/000000.png
    _touch(tmp_path / left, "1403636579763555584.png", "1403636579813555456.png")
    _touch(tmp_path / right, "1403636579763555584.png", "1403636579813555456.png")
    pairs = find_stereo_pairs(tmp_path)
    assert len(pairs.left) == 2 and all(p.parent == tmp_path / left for p in pairs.left)
    assert all(p.parent == tmp_path / right for p in pairs.right)


def test_side_named_anywhere_in_file_names(tmp_path: Path) -> None:
    _touch(tmp_path, "0001_left.png", "0001_right.png", "0002_left.png", "0002_right.png", "0003_left.png")
    pairs = find_stereo_pairs(tmp_path)
    assert [(a.name, b.name) for a, b in zip(pairs.left, pairs.right, strict=True)] == [
        ("0001_left.png", "0001_right.png"), ("0002_left.png", "0002_right.png")]
    assert [p.name for p in pairs.unpaired] == ["0003_left.png"]
