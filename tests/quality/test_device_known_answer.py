"""Known answers: a device-depth recording generated independently (tests/quality/synth_device.py) with a known
bias, relative noise and hole rate gives those figures back through ``s2r depth-quality --depth``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.registry import load_profile
from tests.quality.synth_device import DeviceFrame, render_frame, write_recording

PROFILE = "realsense_d435_848x480"
POSES = [(0.6, 25, 10), (0.9, -20, -5), (1.2, 10, 15), (1.6, -30, 0), (2.0, 15, -10), (2.0, 15, -10), (2.6, 0, 5)]


def _recording(tmp_path: Path, *, bias: float, noise: float, holes: float, seed: int
               ) -> tuple[Path, Path, list[DeviceFrame]]:
    profile = load_profile(PROFILE)
    rng = np.random.default_rng(seed)
    frames = [render_frame(profile.left.K, profile.image_size, (9, 6), 0.08, d, yaw, pitch, bias=bias,
                           rel_noise=noise, hole_rate=holes, rng=rng) for d, yaw, pitch in POSES]
    left, depth = write_recording(tmp_path / "rec", frames)
    return left, depth, frames


def _run(capsys: pytest.CaptureFixture[str], args: list[str]) -> dict:  # type: ignore[type-arg]
    code = main(args)
    out = capsys.readouterr().out
    assert code == 0, out
    return json.loads(out)  # type: ignore[no-any-return]


@pytest.mark.parametrize(("bias", "noise", "holes", "seed"), [(0.012, 0.004, 0.05, 1), (-0.02, 0.01, 0.2, 2)])
def test_known_bias_noise_and_holes_come_back(tmp_path: Path, capsys: pytest.CaptureFixture[str], bias: float,
                                              noise: float, holes: float, seed: int) -> None:
    left, depth, frames = _recording(tmp_path, bias=bias, noise=noise, holes=holes, seed=seed)
    data = _run(capsys, ["depth-quality", PROFILE, "--left", str(left), "--depth", str(depth), "--pattern", "9x6",
                         "--square", "0.08", "--json"])
    fb = 424.0 * 0.05
    assert len(data["frames"]) == len(frames)
    for got, f in zip(data["frames"], frames, strict=True):
        truth = f.truth_m[f.board_mask]
        dist = float(np.median(truth))
        measured = truth * (1 + bias)
        ys, xs = np.nonzero(f.board_mask)  # Intel's plane-fit RMS: perpendicular distances, |n . (x, y, 1)| dz
        K = load_profile(PROFILE).left.K
        along = np.abs(f.R[:, 2] @ np.stack([(xs - K[0, 2]) / K[0, 0], (ys - K[1, 2]) / K[1, 1], np.ones(xs.size)]))
        expect_rms = 100 * noise * float(np.sqrt(np.mean((measured * along) ** 2))) / dist
        expect_subpx = float(np.sqrt(np.mean((fb * noise / measured) ** 2)))
        assert got["distance_m"] == pytest.approx(dist, rel=0.05)  # every frame scored
        assert got["z_accuracy_pct"] == pytest.approx(100 * bias, abs=0.1)
        assert got["plane_fit_rms_pct"] == pytest.approx(expect_rms, rel=0.15)
        assert got["subpixel_rms_px"] == pytest.approx(expect_subpx, rel=0.15)
        assert got["fill_rate_pct"] == pytest.approx(100 * (1 - holes), abs=1.0)
    assert {"frames", "bins"} <= set(data) and data["bins"]
    assert data["datasheet"]["z_accuracy_pct"] == 2.0  # a RealSense profile shows the datasheet's figures
    repeated = data["temporal"]  # poses 4 and 5 repeat: Intel's temporal noise, the median over the ROI of each
    assert len(repeated) == 1 and repeated[0]["frames"] == 2  # pixel's std / median: 0.674 sigma at two frames
    assert repeated[0]["temporal_noise_pct"] == pytest.approx(0.674 * 100 * noise, rel=0.2)


def test_flat_wall_mode(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rng = np.random.default_rng(5)
    folder = tmp_path / "wall"
    folder.mkdir()
    for i in range(3):  # a fronto-parallel wall at 1.5 m, +1 % bias, 0.5 % noise, 10 % holes, as float32 metres
        wall = np.full((480, 848), 1.5 * 1.01, np.float32) * (1 + 0.005 * rng.standard_normal((480, 848)))
        wall[rng.random(wall.shape) < 0.1] = np.nan
        np.save(folder / f"{i}.npy", wall.astype(np.float32))
    data = _run(capsys, ["depth-quality", PROFILE, "--depth", str(folder), "--wall", "--distance", "1.5", "--json"])
    for f in data["frames"]:
        assert f["z_accuracy_pct"] == pytest.approx(1.0, abs=0.1)
        assert f["plane_fit_rms_pct"] == pytest.approx(0.5 * 1.01, rel=0.05)
        assert f["fill_rate_pct"] == pytest.approx(90.0, abs=1.0)
    # Intel's temporal noise of 3 frames: median of per-pixel std (ddof 1) = sigma sqrt(median chi2(2) / 2)
    assert data["temporal"][0]["temporal_noise_pct"] == pytest.approx(0.5 * np.sqrt(2 * np.log(2) / 2), rel=0.1)
