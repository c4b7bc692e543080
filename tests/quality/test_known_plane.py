"""Known answers from an independent numpy-only generator (tests/quality/known_plane.py): a device-depth recording
of a chessboard plane at known distances with known disparity noise, pattern-period mismatches, holes and bias.
Intel's figures must come back, mismatches must be counted and kept out of the RMS, and a frame that cannot be
scored must say why instead of printing a figure."""

from __future__ import annotations

import html
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from s2r.cli import main
from s2r.quality.metrics import FrameQuality, frame_quality
from s2r.quality.plane import Plane
from s2r.quality.report import quality_lines
from s2r.quality.run import QualityResult
from s2r.quality.sanity import insane_reason
from s2r.registry import load_profile
from tests.quality.known_plane import Camera, Frame, expected, render, write_png16

PROFILE = "realsense_d435_848x480"
SIGMA_D = 0.1
BIAS = 0.01


def _camera() -> Camera:
    p = load_profile(PROFILE)
    K = p.left.K
    return Camera(float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]), p.image_size[0], p.image_size[1],
                  p.baseline_m)


def _write(folder: Path, frames: list[Frame]) -> tuple[Path, Path]:
    (folder / "left").mkdir(parents=True)
    (folder / "depth").mkdir()
    for i, f in enumerate(frames):
        write_png16(str(folder / "left" / f"{i:03d}.png"), f.left)
        write_png16(str(folder / "depth" / f"{i:03d}.png"), f.depth_mm)
    return folder / "left", folder / "depth"


def _quality(capsys: pytest.CaptureFixture[str], left: Path, depth: Path) -> dict[str, Any]:
    capsys.readouterr()
    assert main(["-q", "depth-quality", PROFILE, "--left", str(left), "--depth", str(depth), "--pattern", "9x6",
                 "--square", "0.08", "--json"]) == 0
    return json.loads(capsys.readouterr().out)  # type: ignore[no-any-return]


def test_known_noise_mismatches_holes_and_bias_come_back(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cam, rng = _camera(), np.random.default_rng(11)
    poses = [(0.6, 20, 10, 0.10, 0.10), (1.0, -25, -5, 0.05, 0.20), (1.5, 10, 15, 0.15, 0.05), (2.0, 5, -5, 0.0, 0.0)]
    frames = [render(cam, (9, 6), 0.08, d, yaw, pitch, sigma_d_px=SIGMA_D, mismatch_share=mis, hole_share=hole,
                     bias=BIAS, rng=rng) for d, yaw, pitch, mis, hole in poses]
    data = _quality(capsys, *_write(tmp_path / "rec", frames))
    for got, frame in zip(data["frames"], frames, strict=True):
        want = expected(cam, frame, sigma_d_px=SIGMA_D, bias=BIAS)
        assert got["scored"], got
        assert got["distance_m"] == pytest.approx(want["distance_m"], rel=0.01)
        assert got["fill_rate_pct"] == pytest.approx(want["fill_rate_pct"], abs=0.5)
        assert got["outlier_pct"] == pytest.approx(want["outlier_pct"], abs=0.5)  # every mismatch, nothing else
        assert got["subpixel_rms_px"] == pytest.approx(want["subpixel_rms_px"], rel=0.08)  # mismatches left out
        assert got["plane_fit_rms_pct"] == pytest.approx(want["plane_fit_rms_pct"], rel=0.1)
        assert got["z_accuracy_pct"] == pytest.approx(want["z_accuracy_pct"], abs=0.35)  # PnP of the rendered board
    assert {b["frames"] for b in data["bins"]} == {1}


def test_temporal_noise_is_intels_per_pixel_median(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cam, rng = _camera(), np.random.default_rng(12)
    n = 6
    frames = [render(cam, (9, 6), 0.08, 1.2, 10, 5, sigma_d_px=0.15, mismatch_share=0.0, hole_share=0.05, bias=0.0,
                     rng=rng, supersample=2) for _ in range(n)]
    data = _quality(capsys, *_write(tmp_path / "rec", frames))
    (pose,) = data["temporal"]
    assert pose["frames"] == n
    # per pixel: std of depth / depth = z sigma_d / (f B); the median of n-sample standard deviations of a normal
    # is sigma sqrt(median(chi2(n - 1)) / (n - 1))
    chi2 = np.random.default_rng(0).chisquare(n - 1, 400_000)
    factor = float(np.sqrt(np.median(chi2) / (n - 1)))
    z = frames[0].truth_m[frames[0].roi]
    want = 100.0 * float(np.median(z * 0.15 / cam.fb)) * factor
    assert pose["temporal_noise_pct"] == pytest.approx(want, rel=0.08)


def test_frames_that_cannot_be_scored_say_why(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cam, rng = _camera(), np.random.default_rng(13)
    frames = [render(cam, (9, 6), 0.08, 1.0, 5, 5, sigma_d_px=SIGMA_D, mismatch_share=0.7, hole_share=0.0, bias=0.0,
                     rng=rng, supersample=2),
              render(cam, (9, 6), 0.08, 1.3, -5, 5, sigma_d_px=SIGMA_D, mismatch_share=0.0, hole_share=0.9995,
                     bias=0.0, rng=rng, supersample=2)]
    data = _quality(capsys, *_write(tmp_path / "rec", frames))
    dominated, empty = data["frames"]
    assert not dominated["scored"] and dominated["not_scored"].startswith("mismatches dominate")
    assert dominated["outlier_pct"] == pytest.approx(70.0, abs=1.0)
    assert not empty["scored"] and empty["not_scored"].startswith("too few valid pixels")
    for f in data["frames"]:
        assert f["plane_fit_rms_pct"] is None and f["subpixel_rms_px"] is None and f["z_accuracy_pct"] is None
    assert data["verdict"]["level"] == "poor" and all(b["frames"] == 0 for b in data["bins"])


def test_a_figure_that_cannot_be_a_measurement_is_never_printed() -> None:
    absurd = FrameQuality("left11.jpg", 0.306, 0.15, 177800.18, 68.672, 40.4, 1000, 400)
    assert "plane-fit RMS" in insane_reason(absurd) and "sub-pixel RMS" in insane_reason(absurd)
    assert insane_reason(FrameQuality("ok", 1.0, 0.1, 0.5, 0.1, 90.0, 10, 9)) == ""
    # a board matched two squares off everywhere, against its true plane: every pixel a mismatch, nothing scored
    x, y = np.meshgrid(np.linspace(-0.2, 0.2, 40), np.linspace(-0.1, 0.1, 20))
    rays = np.column_stack([x.ravel(), y.ravel()])
    fb, period = 21.2, 30.0
    wrong = np.full(rays.shape[0], fb / (fb / 1.0 + 2 * period))
    got = frame_quality("wrong", wrong, rays, fb_px_m=fb, truth=Plane((0.0, 0.0, 1.0), 1.0), period_px=period)
    assert not got.scored and got.plane_fit_rms_pct is None and "mismatches dominate" in got.not_scored
    result = QualityResult("p", "s", fb, [got, absurd], [])  # even a frame built elsewhere is guarded
    lines = quality_lines(result)
    figures = [line.split("not scored:")[0] for line in lines]  # the columns before the reason
    assert not any("1778" in text or "68.67" in text for text in figures)
    assert any("left11.jpg" in line and "figure not a measurement" in line for line in lines)


def _wall(folder: Path, step_m: float) -> Path:
    rng = np.random.default_rng(5)
    folder.mkdir()
    for i in range(3):
        wall = np.full((480, 848), 1.5, np.float64)
        wall[:, 424:] -= step_m  # a box or a corner in front of half the wall
        wall *= 1 + 0.003 * rng.standard_normal(wall.shape)
        np.save(folder / f"{i}.npy", wall.astype(np.float32))
    return folder


def test_wall_mode_refuses_a_region_that_is_not_a_plane(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    flat = _wall(tmp_path / "flat", 0.0)
    assert main(["-q", "depth-quality", PROFILE, "--depth", str(flat), "--wall", "--distance", "1.5", "--json"]) == 0
    frames = json.loads(capsys.readouterr().out)["frames"]
    assert all(f["scored"] for f in frames)
    assert frames[0]["plane_fit_rms_pct"] == pytest.approx(0.3, rel=0.05)
    step = _wall(tmp_path / "step", 0.3)
    assert main(["-q", "depth-quality", PROFILE, "--depth", str(step), "--wall", "--json"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "not a plane" in err and err.count("\n") == 1


def test_html_page_has_verdict_plots_and_frames(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cam, rng = _camera(), np.random.default_rng(14)
    frames = [render(cam, (9, 6), 0.08, d, 10, 5, sigma_d_px=SIGMA_D, mismatch_share=mis, hole_share=0.1, bias=0.0,
                     rng=rng, supersample=2) for d, mis in ((0.8, 0.05), (1.6, 0.7))]
    left, depth = _write(tmp_path / "rec", frames)
    assert main(["-q", "depth-quality", PROFILE, "--left", str(left), "--depth", str(depth), "--pattern", "9x6",
                 "--square", "0.08", "--report", str(tmp_path / "rep")]) == 0
    out = capsys.readouterr().out
    assert out.startswith("depth quality of realsense_d435_848x480 (device depth): CHECK: 1/2 frames scored")
    page = html.unescape((tmp_path / "rep" / "depth_quality.html").read_text())
    assert page.index("CHECK: 1/2 frames scored") < page.index("Metrics against distance") < page.index("Frames:")
    assert page.count("data:image/png;base64,") == 5 + 2  # five metrics against distance, two frames
    for text in ("theory, Intel's model", "datasheet: < 2 % at 2 m", "mismatches dominate",
                 "region of interest (red) and depth"):
        assert text in page or text in out, text
