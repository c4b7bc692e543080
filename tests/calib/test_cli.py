"""`s2r calibrate` end to end on synthetic sets: profile, JSON, report, cache, mono, globs, joint refinement."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.cli import main
from s2r.formats.s2r_yaml import load_mono_profile, load_profile_file
from s2r.profile import StereoProfile

#: The board of these sets (`calibrate` has no default board).
BOARD = ("--pattern", "9x6", "--square", "0.025")


def test_known_rig_via_cli_with_report_and_cache(synthetic_set: tuple[Path, StereoProfile], tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    folder, truth = synthetic_set
    out, report = tmp_path / "rig.yaml", tmp_path / "report"
    code = main(["calibrate", *BOARD, str(folder), "-o", str(out), "--json", "--report", str(report), "--jobs", "2"])
    first = json.loads(capsys.readouterr().out)
    assert code == 0 and first["detections_from_cache"] == 0
    profile = load_profile_file(out)
    assert profile.name == "rig" and abs(profile.left.fx_px - truth.left.fx_px) < 0.0015 * truth.left.fx_px
    q = profile.provenance.calibration
    assert q is not None and q.views_used + len(q.views_dropped) == 30 and q.coverage_left is not None
    assert all(len(s.sha256) == 64 for s in profile.provenance.sources)
    page = (report / "index.html").read_text()
    # errors, thumbnails, residual vectors, board poses, projection uncertainty, coverage, overlay, rectified pair
    assert page.count("data:image/png;base64,") == 8
    for title in ("Per-view errors", "Coverage", "rectified pair", "relative std", "Lens model comparison",
                  "held-out RMS", "board poses in 3D", "residual vectors", "Tx (mm, signed)", "Projection uncertainty",
                  "Board: chessboard 9x6 inner corners, 25 mm squares", "Stereo held-out error", "jackknife"):
        assert title in page
    assert page.index("Verdict") < page.index("Summary") and first["verdict"]["level"] in ("good", "check", "poor")
    assert first["model_comparison"]["models"][0]["chosen"] and len(first["views"]) == q.views_used + sum(
        d.reason.startswith("outlier") for d in q.views_dropped)
    # a re-run with only a solver option changed reads every detection from the cache next to the output
    code = main(["calibrate", *BOARD, str(folder), "-o", str(out), "--json", "--force", "--max-error", "0.5"])
    second = json.loads(capsys.readouterr().out)
    assert code == 0 and second["detections_from_cache"] == 60
    assert (tmp_path / "rig.yaml.corners").is_dir()


def test_fix_intrinsics_ros_way_recovers_the_rig(synthetic_set: tuple[Path, StereoProfile], tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    """--fix-intrinsics (ROS's way: the joint solve is the default now, the old --refine-joint)."""
    folder, truth = synthetic_set
    out = tmp_path / "fixed.yaml"
    assert main(["-q", "calibrate", *BOARD, str(folder), "-o", str(out), "--fix-intrinsics", "--no-cache",
                 "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    p = load_profile_file(out)
    assert "CALIB_FIX_INTRINSIC" in p.provenance.method
    # a rotation std like the joint solve's (the intrinsics' uncertainty propagated), and an honest one
    angle = np.degrees(np.linalg.norm(cv2.Rodrigues(p.R @ truth.R.T)[0]))
    assert figures["rotation_std_deg"] is not None and 0 < figures["rotation_std_deg"] < 0.2
    assert angle <= 3 * figures["rotation_std_deg"]
    for cam, true in ((p.left, truth.left), (p.right, truth.right)):
        # 0.25 %: ROS's way rejects no corners, and the plain retry also finds right/03's nearly edge-on board
        assert abs(cam.fx_px - true.fx_px) < 0.0025 * true.fx_px
        assert abs(cam.cx_px - true.cx_px) < 0.7 and abs(cam.cy_px - true.cy_px) < 0.7
    b_std = p.extrinsics.baseline_std_m
    assert b_std is not None and abs(p.baseline_m - truth.baseline_m) <= min(3 * b_std, 0.002 * truth.baseline_m)


def test_mono_calibration_writes_a_camera_profile(synthetic_set: tuple[Path, StereoProfile], tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    folder, truth = synthetic_set
    out = tmp_path / "mono.yaml"
    code = main(["calibrate", *BOARD, "--mono", "--left", str(folder / "right" / "*.png"), "-o", str(out), "--json",
                 "--report", str(tmp_path / "rep")])
    figures = json.loads(capsys.readouterr().out)
    assert code == 0 and figures["quality"]["views_used"] >= 25
    cam = load_mono_profile(out).camera
    # 0.25 %: no corner rejection here, and the plain retry also finds right/03's nearly edge-on board
    assert abs(cam.fx_px - truth.right.fx_px) < 0.0025 * truth.right.fx_px
    assert cam.std is not None and cam.std.fx_px is not None
    assert abs(cam.fx_px - truth.right.fx_px) <= 3 * cam.std.fx_px
    html = (tmp_path / "rep" / "index.html").read_text()
    assert "Per-view errors" in html and "Verdict" in html and "Lens model comparison" in html
    # a verdict and the held-out model comparison, as for a pair
    assert figures["verdict"]["level"] in ("good", "check", "poor") and figures["verdict"]["reasons"]
    models = figures["model_comparison"]["models"]
    assert [m["model"] for m in models if m["chosen"]] == ["k1k2p1p2"] and all(m["heldout_px"] > 0 for m in models)
    # the held-out error over 4 folds and both std (the larger written to the profile) are in --json
    held = figures["heldout"]
    assert held["folds"] == 4 and 0 < held["heldout_px"] <= held["heldout_all_px"]
    assert cam.std.fx_px == held["parameters"]["fx"]["std"] and held["parameters"]["fx"]["std_source"] in (
        "covariance", "jackknife")
    assert figures["board"] == "chessboard 9x6 inner corners, 25 mm squares" and "Held-out error" in html
    assert "chessboard 9x6 inner corners, 25 mm squares" in html and "4-fold jackknife" in html
    assert "Projection uncertainty" in html and figures["projection_uncertainty"]["camera"]["covariance"]


def test_prefixed_files_and_globs_pair_by_number(synthetic_set: tuple[Path, StereoProfile], tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    folder, _ = synthetic_set
    flat = tmp_path / "flat"
    flat.mkdir()
    for i in range(8):
        shutil.copy(folder / "left" / f"{i:02d}.png", flat / f"left{i + 1:02d}.png")
        shutil.copy(folder / "right" / f"{i:02d}.png", flat / f"right{i + 1}.png")  # no zero padding
    code = main(["calibrate", *BOARD, str(flat), "-o", str(tmp_path / "a.yaml"), "--json", "--jobs", "1"])
    a = json.loads(capsys.readouterr().out)
    code_b = main(["calibrate", *BOARD, "--left", str(flat / "left*.png"), "--right", str(flat / "right*.png"),
                   "-o", str(tmp_path / "b.yaml"), "--json", "--jobs", "1"])
    b = json.loads(capsys.readouterr().out)
    assert code == code_b == 0
    assert a["quality"]["views_used"] == b["quality"]["views_used"] == 8 - len(a["dropped"])
    assert a["baseline_m"] == pytest.approx(b["baseline_m"])


@pytest.mark.parametrize(("model", "terms", "name"), [("plumb_bob", 5, "plumb_bob"),
                                                      ("rational", 8, "rational_polynomial")])
def test_distortion_models(synthetic_set: tuple[Path, StereoProfile], tmp_path: Path, model: str, terms: int,
                           name: str, capsys: pytest.CaptureFixture[str]) -> None:
    folder, truth = synthetic_set
    out = tmp_path / f"{model}.yaml"
    assert main(["-q", "calibrate", *BOARD, str(folder), "-o", str(out), "--distortion", model, "--jobs", "1"]) == 0
    capsys.readouterr()
    p = load_profile_file(out)
    assert p.left.distortion.model == name and len(p.left.distortion.coefficients) == terms
    assert p.provenance.calibration is not None and p.provenance.calibration.distortion_terms == model
    assert abs(p.left.fx_px - truth.left.fx_px) < 0.005 * truth.left.fx_px
    # rational terms trade off against each other, so compare the mapping, not k1: undistort a pixel grid
    # over the central 80 % of the image with both models and compare (in pixels at the true focal length)
    grid = np.stack(np.meshgrid(np.linspace(64, 576, 9), np.linspace(48, 432, 7)), -1).reshape(-1, 1, 2)
    got = cv2.undistortPoints(grid, p.left.K, p.left.D).reshape(-1, 2)
    want = cv2.undistortPoints(grid, truth.left.K, truth.left.D).reshape(-1, 2)
    assert np.abs(got - want).max() * truth.left.fx_px < 1.0


def test_max_error_drops_and_lists_views(synthetic_set: tuple[Path, StereoProfile], tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    folder, _ = synthetic_set
    assert main(["calibrate", *BOARD, str(folder), "-o", str(tmp_path / "a.yaml"), "--json", "--jobs", "1"]) == 0
    errors = sorted(v["stereo_px"] for v in json.loads(capsys.readouterr().out)["views"] if v["used"])
    limit = errors[-4]  # the three worst views exceed it
    assert main(["calibrate", *BOARD, str(folder), "-o", str(tmp_path / "b.yaml"), "--json", "--jobs", "1",
                 "--max-error", f"{limit:.6f}"]) == 0
    figures = json.loads(capsys.readouterr().out)
    outliers = [d for d in figures["dropped"] if d["reason"].startswith("outlier")]
    assert len(outliers) >= 3 and all(d["rms_px"] > 0 for d in outliers)
    assert all(f"> {limit:.3f} px" in d["reason"] for d in outliers)
    assert figures["quality"]["views_used"] == figures["quality"]["views_detected"] - len(outliers)
