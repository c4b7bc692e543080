"""``s2r sensor fit`` gives back the sensor two s2r-free generators (tests/sensor/recordings.py) recorded with."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from tests.sensor.recordings import POSES, Truth, device_recording, stereo_recording, write_profile

DEVICE_TRUTH = Truth(sigma_d_px=0.1, sigma_growth_px_per_m=0.03, fill=[(0.5, 97.0), (2.0, 80.0)],
                     edge_band_px=4.0, hole_scale_px=1.0)
STEREO_TRUTH = Truth(noise_dn=2.5, blur_px=1.2)


def _fit(capsys: pytest.CaptureFixture[str], tmp: Path, *inputs: str) -> dict:
    code = main(["sensor", "fit", "--profile", str(write_profile(tmp / "rig.yaml")), *inputs, "--pattern", "9x6",
                 "--square", "0.04", "-o", str(tmp / "sensor.yaml"), "--json"])
    assert code == 0
    return json.loads(capsys.readouterr().out)


@pytest.fixture(scope="module")
def device_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return device_recording(tmp_path_factory.mktemp("device") / "rec", DEVICE_TRUTH)


def test_device_depth_fit_gives_back_sigma_d_fill_and_band(device_dir: Path, tmp_path: Path,
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    got = _fit(capsys, tmp_path, "--left", str(device_dir / "left"), "--depth", str(device_dir / "depth"))
    assert got["subpixel_sigma_px"] == pytest.approx(DEVICE_TRUTH.sigma_d_px, rel=0.15)  # sigma_d at 1 m
    assert got["subpixel_growth_px_per_m"] == pytest.approx(DEVICE_TRUTH.sigma_growth_px_per_m, abs=0.015)
    assert len(got["fill_rate_by_distance"]) >= 3
    for point in got["fill_rate_by_distance"]:
        truth = 100 * float(DEVICE_TRUTH.fill_at(np.array(point["distance_m"])))
        assert abs(point["fill_rate_pct"] - truth) <= 2.0, (point, truth)
    assert got["edge_dropout_px"] == pytest.approx(DEVICE_TRUTH.edge_band_px, rel=0.25)
    assert got["hole_scale_px"] == pytest.approx(DEVICE_TRUTH.hole_scale_px, rel=0.3)
    assert got["image_noise_dn"] == pytest.approx(1.0, rel=0.15)  # the infrared images: 1 DN, blur 0.7 px
    assert got["blur_sigma_px"] == pytest.approx(0.7, rel=0.2)
    assert (tmp_path / "sensor.yaml").read_text().startswith("# s2r sensor model")


def test_independent_holes_wide_band_float_depth(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    truth = Truth(sigma_d_px=0.2, fill=[(0.5, 85.0), (2.0, 85.0)], edge_band_px=8.0, hole_scale_px=0.0)
    rec = device_recording(tmp_path / "rec", truth, npy=True, seed=7)
    got = _fit(capsys, tmp_path, "--left", str(rec / "left"), "--depth", str(rec / "depth"))
    assert got["subpixel_sigma_px"] == pytest.approx(0.2, rel=0.15)
    assert abs(got["subpixel_growth_px_per_m"]) < 0.03
    for point in got["fill_rate_by_distance"]:
        assert abs(point["fill_rate_pct"] - 85.0) <= 2.0, point
    assert got["edge_dropout_px"] == pytest.approx(8.0, rel=0.25)
    assert got["hole_scale_px"] < 0.3
    for row in got["subpixel_sigma_by_distance"]:
        assert row["subpixel_sigma_px"] == pytest.approx(0.2, rel=0.15)


def test_stereo_fit_gives_back_image_noise_and_blur(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rec = stereo_recording(tmp_path / "rec", STEREO_TRUTH)
    got = _fit(capsys, tmp_path, "--left", str(rec / "left"), "--right", str(rec / "right"))
    assert got["image_noise_dn"] == pytest.approx(STEREO_TRUTH.noise_dn, rel=0.15)
    assert got["blur_sigma_px"] == pytest.approx(STEREO_TRUTH.blur_px, rel=0.2)
    assert got["notes"]["image_noise_dn"].startswith("flat squares")
    assert got["subpixel_sigma_px"] is not None and got["fill_rate_by_distance"]


def test_clipped_board_noise(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    truth = Truth(noise_dn=3.0, blur_px=1.0)
    rec = stereo_recording(tmp_path / "rec", truth, poses=POSES[:3], levels=(0.0, 255.0))
    got = _fit(capsys, tmp_path, "--left", str(rec / "left"))
    assert got["image_noise_dn"] == pytest.approx(truth.noise_dn, rel=0.15)  # every square clipped: censored fit
    assert got["blur_sigma_px"] == pytest.approx(truth.blur_px, rel=0.2)


def test_still_frames_give_temporal_noise(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    truth = Truth(noise_dn=1.5, blur_px=0.8)
    rec = stereo_recording(tmp_path / "rec", truth, poses=[(0.7, 10, -10, (0.0, 0.0))], still_repeats=3)
    got = _fit(capsys, tmp_path, "--left", str(rec / "left"))
    assert got["notes"]["image_noise_dn"].startswith("temporal")
    assert got["image_noise_dn"] == pytest.approx(truth.noise_dn, rel=0.15)
    assert got["blur_sigma_px"] == pytest.approx(truth.blur_px, rel=0.2)
    assert got["subpixel_sigma_px"] is None  # images only: no depth figure is made up
