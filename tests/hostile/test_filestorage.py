"""Issue 14 item 4: OpenCV FileStorage files are read by s2r's safe reader, never by cv2.FileStorage (which
corrupts memory on a matrix without ``cols``); YAML duplicate keys and object tags are refused."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.errors import FormatError, ProfileError
from s2r.formats.filestorage import read_filestorage
from s2r.formats.opencv import load_opencv
from s2r.formats.s2r_yaml import load_profile_file as load_profile

REPO = Path(__file__).resolve().parents[2]
NO_COLS = """%YAML:1.0
---
M1: !!opencv-matrix
   rows: 3
   dt: d
   data: [ 500., 0., 320., 0., 500., 240., 0., 0., 1. ]
"""
LAUGHS = """<?xml version="1.0"?>
<!DOCTYPE lolz [<!ENTITY lol "lol"><!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
<!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">]>
<opencv_storage><name>&lol3;</name></opencv_storage>
"""
XXE = """<?xml version="1.0"?>
<!DOCTYPE x [<!ENTITY secret SYSTEM "file:///etc/passwd">]>
<opencv_storage><name>&secret;</name></opencv_storage>
"""


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_missing_cols_is_a_clean_error_in_ten_cli_runs(tmp_path: Path) -> None:
    """The finding's file: under cv2.FileStorage it aborted (exit 134/139) in some runs. Ten runs, each exit 2
    with one line naming M1.cols (the reader never hands the file to OpenCV)."""
    src = _write(tmp_path, "nocols.yml", NO_COLS)
    code = ("import sys\nfrom s2r.cli import main\ncodes = [main(['profile', 'convert', sys.argv[1], '--to', 's2r', "
            "'-o', sys.argv[2] + str(i)]) for i in range(10)]\nprint(codes)")
    result = subprocess.run([sys.executable, "-c", code, str(src), str(tmp_path / "out")], capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 0 and result.stdout.strip() == str([2] * 10), result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 10 and all("M1.cols: required field" in line for line in lines)
    assert not list(tmp_path.glob("out*"))


@pytest.mark.parametrize(("text", "fragment"), [
    (NO_COLS.replace("   dt: d\n", "   cols: 3\n"), "M1.dt"),
    (NO_COLS.replace("rows: 3", "rows: 3\n   cols: 4"), "holds 9 numbers"),
    (NO_COLS.replace("rows: 3", "rows: 100000\n   cols: 100000"), "larger than"),
    (NO_COLS.replace("rows: 3", "rows: -3\n   cols: 3"), "M1.rows"),
    (NO_COLS.replace("rows: 3", "rows: 3\n   cols: 3").replace("dt: d", "dt: zz"), "unknown element type"),
    (NO_COLS.replace("rows: 3", "rows: 3\n   cols: 3").replace("500., 0.,", "abc, 0.,"), "not a number"),
    (NO_COLS.replace("rows: 3", "rows: 3\n   rows: 3"), "duplicate key 'rows'"),
    (NO_COLS + "M1: 5\n", "duplicate key 'M1'"),
    (NO_COLS.replace("!!opencv-matrix", "!!python/object/apply:os.system"), "malformed or truncated"),
    (LAUGHS, "DOCTYPE"),
    (XXE, "DOCTYPE"),
    ("<opencv_storage><M1>1</M1><M1>2</M1></opencv_storage>", "duplicate node"),
    ('<opencv_storage><M1 type_id="opencv-matrix"><rows>3</rows><dt>d</dt><data>1 2 3</data></M1></opencv_storage>',
     "M1.cols"),
    ("<opencv_storage><M1>1</M1>", "malformed XML"),
])
def test_malformed_filestorage_is_one_line(tmp_path: Path, text: str, fragment: str) -> None:
    path = _write(tmp_path, "bad.xml" if text.startswith("<") else "bad.yml", text)
    with pytest.raises(FormatError) as info:
        read_filestorage(path)
    message = str(info.value)
    assert fragment in message and "\n" not in message and str(path) in message
    assert "root:" not in message and "lol" not in message


@pytest.mark.parametrize("ext", ["yml", "xml"])
def test_agrees_with_opencv_on_files_opencv_wrote(tmp_path: Path, ext: str) -> None:
    """Anchor: on well-formed files written by cv2.FileStorage, the safe reader returns what cv2 reads."""
    rng = np.random.default_rng(14)
    values = {"M1": rng.normal(size=(3, 3)) * 300, "D1": rng.normal(size=(1, 5)) * 1e-3,
              "R": rng.normal(size=(3, 3)).astype(np.float32), "T": rng.normal(size=(3, 1)) * 1e-5,
              "px": rng.integers(0, 255, size=(2, 3, 3)).astype(np.uint8)}
    path = tmp_path / f"rig.{ext}"
    storage = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    for key, value in values.items():
        storage.write(key, value)
    storage.write("image_width", 848)
    storage.write("distortion_model", "plumb_bob")
    storage.write("scale", 2.5e-7)
    storage.release()
    nodes = read_filestorage(path)
    check = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    for key in values:
        expected = np.asarray(check.getNode(key).mat(), dtype=np.float64)
        assert nodes[key].shape == expected.shape  # type: ignore[union-attr]
        np.testing.assert_array_equal(nodes[key], expected)
    assert nodes["image_width"] == 848.0 and nodes["distortion_model"] == "plumb_bob"
    assert nodes["scale"] == check.getNode("scale").real()
    check.release()


def test_duplicate_key_in_a_profile_is_refused(tmp_path: Path) -> None:
    text = (REPO / "profiles" / "real" / "realsense_d435_848x480.yaml").read_text(encoding="utf-8")
    text = text.replace("  fx_px:", "  fx_px: 1.0\n  fx_px:", 1)
    path = _write(tmp_path, "dup.yaml", text)
    with pytest.raises(ProfileError, match=r"line \d+: malformed YAML: duplicate key 'fx_px'"):
        load_profile(path)


@pytest.mark.parametrize("tag", ["!!python/object/apply:os.system ['true']", "!!binary aGVsbG8=", "!!set {a, b}"])
def test_object_tags_are_refused(tmp_path: Path, tag: str) -> None:
    text = (REPO / "profiles" / "real" / "realsense_d435_848x480.yaml").read_text(encoding="utf-8")
    path = _write(tmp_path, "tag.yaml", text.replace("description:", f"extra: {tag}\ndescription:", 1))
    with pytest.raises(ProfileError, match="malformed YAML"):
        load_profile(path)


def test_opencv_import_of_a_well_formed_file_still_works(tmp_path: Path) -> None:
    from s2r.formats.opencv import dump_opencv
    from s2r.registry import load_profile as by_name

    profile = by_name(str(REPO / "profiles" / "real" / "realsense_d435_848x480.yaml"))
    for ext in ("yml", "xml"):
        back = load_opencv(dump_opencv(profile, tmp_path / f"p.{ext}"))
        assert back.left.fx_px == pytest.approx(profile.left.fx_px) and back.baseline_m == pytest.approx(
            profile.baseline_m)
