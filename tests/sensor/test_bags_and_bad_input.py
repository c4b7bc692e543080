"""``s2r sensor fit`` from ROS 2 bags (written with rosbags' writer) equals the folder fit; bad input is one line."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

from s2r.cli import main
from tests.sensor.recordings import Truth, device_recording, stereo_recording, write_profile

pytest.importorskip("rosbags")
from rosbags.rosbag2 import Writer
from rosbags.typesys import Stores, get_typestore

IMAGE = "sensor_msgs/msg/Image"
FIT = ["--pattern", "9x6", "--square", "0.04", "--json"]


def _msg(ts: Any, image: np.ndarray, stamp_ns: int, encoding: str) -> Any:
    Image, Header, Time = ts.types[IMAGE], ts.types["std_msgs/msg/Header"], ts.types["builtin_interfaces/msg/Time"]
    header = Header(stamp=Time(sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9), frame_id="camera")
    h, w = image.shape
    data = np.ascontiguousarray(image).view(np.uint8).reshape(-1)
    return Image(header=header, height=h, width=w, encoding=encoding, is_bigendian=0, step=w * image.itemsize,
                 data=data)


def _bag(path: Path, rec: Path, second: str, encoding: str) -> Path:
    ts = get_typestore(Stores.ROS2_HUMBLE)
    with Writer(path, version=9) as writer:
        left = writer.add_connection("/left", IMAGE, typestore=ts)
        other = writer.add_connection(f"/{second}", IMAGE, typestore=ts)
        for i, (a, b) in enumerate(zip(sorted((rec / "left").iterdir()), sorted((rec / second).iterdir()),
                                       strict=True)):
            t = 10**9 + i * 10**8
            writer.write(left, t, ts.serialize_cdr(_msg(ts, cv2.imread(str(a), cv2.IMREAD_GRAYSCALE), t, "mono8"),
                                                   IMAGE))
            image = cv2.imread(str(b), cv2.IMREAD_UNCHANGED if second == "depth" else cv2.IMREAD_GRAYSCALE)
            writer.write(other, t, ts.serialize_cdr(_msg(ts, image, t, encoding), IMAGE))
    return path


def _fit(capsys: pytest.CaptureFixture[str], args: list[str]) -> dict:
    assert main(["sensor", "fit", *args, *FIT]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("kind", ["depth", "right"])
def test_bag_fit_equals_folder_fit(kind: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rig = str(write_profile(tmp_path / "rig.yaml"))
    truth = Truth(sigma_d_px=0.1, fill=[(0.5, 90.0), (2.0, 90.0)], edge_band_px=4.0, noise_dn=2.0, blur_px=1.0)
    poses = [(0.65, 10, -10, (0.0, 0.0)), (0.9, -10, 10, (0.0, 0.0)), (1.2, 5, 15, (0.0, 0.0))]
    rec = (device_recording(tmp_path / "rec", truth, poses=poses) if kind == "depth"
           else stereo_recording(tmp_path / "rec", truth, poses=poses))
    bag = _bag(tmp_path / "bag", rec, kind, "16UC1" if kind == "depth" else "mono8")
    folder = _fit(capsys, ["--profile", rig, "--left", str(rec / "left"), f"--{kind}", str(rec / kind),
                           "-o", str(tmp_path / "a.yaml")])
    from_bag = _fit(capsys, ["--profile", rig, "--bag", str(bag), "--left-topic", "/left", f"--{kind}-topic",
                             f"/{kind}", "-o", str(tmp_path / "b.yaml")])
    for key in ("image_noise_dn", "blur_sigma_px", "subpixel_sigma_px", "fill_rate_by_distance"):
        assert from_bag[key] == pytest.approx(folder[key]) if not isinstance(folder[key], list) else \
            from_bag[key] == folder[key]


def _err(capsys: pytest.CaptureFixture[str], args: list[str]) -> str:
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and "Traceback" not in err
    return err


def test_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rig = str(write_profile(tmp_path / "rig.yaml"))
    base = ["sensor", "fit", "--profile", rig, "--pattern", "9x6", "--square", "0.04", "-o", str(tmp_path / "s.yaml")]
    assert "--left" in _err(capsys, base)
    assert "--right/--depth" in _err(capsys, [*base, "--left", "x", "--right", "y", "--depth", "z"])
    assert "--right-topic/--depth-topic" in _err(capsys, [*base, "--bag", "b", "--left-topic", "/l"])
    assert "--square" in _err(capsys, [*base[:-4], "--square", "nan", "-o", str(tmp_path / "s.yaml"), "--left", "x"])
    assert "no such folder" in _err(capsys, [*base, "--left", str(tmp_path / "missing")])
    blank = tmp_path / "blank"
    blank.mkdir()
    cv2.imwrite(str(blank / "00.png"), np.full((240, 320), 128, np.uint8))
    assert "chessboard" in _err(capsys, [*base, "--left", str(blank)])
    assert not (tmp_path / "s.yaml").exists()
    model = tmp_path / "m.yaml"
    model.write_text("blur_sigma_px: -1\n")
    assert "blur_sigma_px" in _err(capsys, ["sensor", "apply", str(model), str(blank), "--profile", rig, "-o",
                                            str(tmp_path / "out")])
    assert "sensor" in _err(capsys, ["render", "boards", rig, "--sensor-model", rig, "-o", str(tmp_path / "r")])
