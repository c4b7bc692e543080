"""RealSense recordings (librealsense .db3) written by Intel's pyrealsense2: values come back as pyrealsense2 reads
them, the extrinsics convention, provenance, and hostile files (one line, exit 2)."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.errors import FormatError
from s2r.formats.realsense.recording import load_realsense_recording, read_recording
from s2r.formats.s2r_yaml import load_profile_file
from tests.formats import realsense_writer as rw


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("rs") / "rec.db3"
    rw.write(path, rw.Spec())
    return path


def test_intrinsics_and_depth_scale_equal_pyrealsense2_reading(recording: Path) -> None:
    ref = rw.playback(recording)
    rig = load_realsense_recording(recording)
    for cam, intr, spec_k in ((rig.left, ref["ir1"], rw.Spec().ir1), (rig.right, ref["ir2"], rw.Spec().ir2)):
        # exactly pyrealsense2's float32 values (the recording keeps them exactly)
        assert (cam.fx_px, cam.fy_px, cam.cx_px, cam.cy_px) == (intr.fx, intr.fy, intr.ppx, intr.ppy)
        assert list(cam.distortion.coefficients) == list(intr.coeffs)
        np.testing.assert_allclose([cam.fx_px, cam.fy_px, cam.cx_px, cam.cy_px], spec_k, rtol=1e-7)
        assert cam.distortion.model == "plumb_bob" and (cam.width_px, cam.height_px) == (64, 48)
    assert rig.left.fx_px != rig.right.fx_px
    facts = read_recording(recording)
    assert np.float32(facts.depth_units_m) == np.float32(ref["depth_scale"])
    notes = rig.provenance.notes
    assert ref["serial"] in notes and ref["firmware"] in notes and ref["name"] in notes and "0.00025 m" in notes
    assert rig.provenance.method == "imported from librealsense recording (ROS 2 sqlite3)"


def test_extrinsics_follow_rs2_transform_point_to_point(recording: Path) -> None:
    """X_right = R X_left + T is what rs2_transform_point_to_point(get_extrinsics_to(IR1 -> IR2)) computes."""
    ref = rw.playback(recording)
    rig = load_realsense_recording(recording)
    spec = rw.Spec()
    assert not np.allclose(rig.R, np.eye(3), atol=1e-3)
    # the recording prints 6 decimals: each element within 5e-7 (+ float32 rounding of pyrealsense2's reading)
    np.testing.assert_allclose(rig.R, np.reshape(ref["rotation"], (3, 3)).T, atol=1e-6)
    np.testing.assert_allclose(rig.T, ref["translation"], atol=1e-6)
    np.testing.assert_allclose(rig.R, spec.R, atol=1e-6)
    np.testing.assert_allclose(rig.T, spec.t, atol=1e-6)
    rs = ref["rs"]
    for point in ([0.0, 0.0, 1.0], [0.3, -0.2, 2.5], [-1.0, 0.5, 0.7]):
        theirs = rs.rs2_transform_point_to_point(ref["extrinsics"], point)
        np.testing.assert_allclose(rig.R @ point + rig.T, theirs, atol=3e-6)


def test_cli_convert_writes_the_profile(recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "real.yaml"
    assert main(["profile", "convert", str(recording), "--to", "s2r", "-o", str(out)]) == 0
    assert "librealsense recording (ROS 2 sqlite3)" in capsys.readouterr().out
    rig = load_profile_file(out)
    assert rig.name == "realsense_123456789012_64x48" and rig.baseline_m == pytest.approx(0.05005, abs=1e-4)


def _copy(recording: Path, tmp: Path, sql: str = "", args: tuple = ()) -> Path:
    path = tmp / "bad.db3"
    path.write_bytes(recording.read_bytes())
    if sql:
        with sqlite3.connect(path) as conn:
            conn.execute(sql, args)
    return path


def _cdr_string(text: str) -> bytes:
    raw = text.encode() + b"\0"
    return b"\x00\x01\x00\x00" + len(raw).to_bytes(4, "little") + raw


def _hostile(recording: Path, tmp: Path, case: str) -> Path:
    if case == "text":
        path = tmp / "notes.db3"
        path.write_text("hello\n")
        return path
    if case == "random":
        path = tmp / "noise.db3"
        path.write_bytes(b"SQLite format 3\0" + bytes(np.random.default_rng(1).integers(0, 256, 5000, np.uint8)))
        return path
    if case == "truncated":
        path = tmp / "cut.db3"
        path.write_bytes(recording.read_bytes()[:20000])
        return path
    if case == "empty-sqlite":
        path = tmp / "empty.db3"
        with sqlite3.connect(path) as conn:
            conn.execute("CREATE TABLE t(x)")
        return path
    if case == "no-ir2":
        return _copy(recording, tmp, "DELETE FROM topics WHERE name LIKE '%Infrared_2%'")
    if case == "huge-size":
        text = "width=100000;height=100000;fx=1;ppx=1;fy=1;ppy=1;model=Brown Conrady;coeffs=0,0,0,0,0"
        path = _copy(recording, tmp, "UPDATE messages SET data = ? WHERE topic_id = (SELECT id FROM topics WHERE "
                     "name = '/device_0/sensor_0/Infrared_2/camera_info')", (_cdr_string(text),))
        with sqlite3.connect(path) as conn:
            conn.execute("DELETE FROM topics WHERE name = '/device_0/sensor_0/Infrared_2/image/camera_info'")
        return path
    if case == "garbage-cdr":
        return _copy(recording, tmp, "UPDATE messages SET data = ? WHERE topic_id = (SELECT id FROM topics WHERE "
                     "name = '/device_0/sensor_0/Infrared_2/tf/ref_1')", (b"\x00\x01\x00\x00\xff\xff\xff\x7f",))
    raise AssertionError(case)


@pytest.mark.parametrize("case", ["text", "random", "truncated", "empty-sqlite", "no-ir2", "huge-size",
                                  "garbage-cdr"])
def test_hostile_recordings_one_line_exit_2(case: str, recording: Path, tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    bad = _hostile(recording, tmp_path, case)
    out = tmp_path / "x.yaml"
    capsys.readouterr()
    assert main(["profile", "convert", str(bad), "--to", "s2r", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err and bad.name in err, err
    assert not out.exists()
    with pytest.raises(FormatError):
        load_realsense_recording(bad)
