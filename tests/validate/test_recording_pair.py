"""validate with both sides from recordings: two device-depth recordings from the independent generator
(tests/quality/known_plane.py) measured with the same metrics per bin, bootstrap intervals and verdicts."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.errors import DepthError
from s2r.formats.s2r_yaml import dump_profile
from s2r.quality.source import parse_source
from s2r.registry import load_profile
from s2r.validate.recording.compare import compare_recordings, recording_checks
from s2r.validate.recording.report import recording_lines, recording_sections
from s2r.validate.tolerances import Tolerances
from tests.conftest import make_rig
from tests.quality.known_plane import Camera, render, write_png16

PROFILE = "realsense_d435_848x480"
POSES = [(0.6, 15, 5), (0.65, -10, 8), (1.2, 20, 0), (1.3, -15, 5)]


def _recording(folder: Path, *, sigma_d: float, holes: float, seed: int) -> Path:
    p = load_profile(PROFILE)
    K = p.left.K
    cam = Camera(float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]), p.image_size[0], p.image_size[1],
                 p.baseline_m)
    rng = np.random.default_rng(seed)
    (folder / "left").mkdir(parents=True)
    (folder / "depth").mkdir()
    for i, (d, yaw, pitch) in enumerate(POSES):
        f = render(cam, (9, 6), 0.08, d, yaw, pitch, sigma_d_px=sigma_d, mismatch_share=0.05, hole_share=holes,
                   bias=0.0, rng=rng, supersample=2)
        write_png16(str(folder / "left" / f"{i:03d}.png"), f.left)
        write_png16(str(folder / "depth" / f"{i:03d}.png"), f.depth_mm)
    return folder


@pytest.fixture(scope="module")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("recs")
    return {"real": _recording(root / "real", sigma_d=0.1, holes=0.1, seed=1),
            "twin": _recording(root / "twin", sigma_d=0.1, holes=0.1, seed=2),
            "noisy": _recording(root / "noisy", sigma_d=0.3, holes=0.3, seed=3)}


def test_a_twin_recording_agrees_in_every_bin(recordings: dict[str, Path]) -> None:
    profile = load_profile(PROFILE)
    comparison = compare_recordings(profile, profile, sim_source=str(recordings["twin"]),
                                    real_source=str(recordings["real"]), pattern=(9, 6), square_m=0.08,
                                    preset="profile", tol=Tolerances())
    assert [(r["lo_m"], r["real_frames"], r["sim_frames"]) for r in comparison.rows] == [(0.5, 2, 2), (1.0, 2, 2)]
    for row in comparison.rows:
        assert row["passed"] is True, row["verdict"]
        sub = next(m for m in row["metrics"] if m["metric"] == "subpixel_rms_px")
        assert sub["real"] == pytest.approx(0.1, rel=0.1) and sub["sim"] == pytest.approx(0.1, rel=0.1)
        assert sub["real_ci"][0] <= sub["real"] <= sub["real_ci"][1] and sub["gap_ci"] is not None
    assert all(c.passed for c in recording_checks(comparison))
    data = comparison.as_dict()
    assert data["sim_mode"] == "recording" and data["sim"]["frames"] and data["real"]["frames"]
    assert any("sim recording" in line for line in recording_lines(comparison))
    assert recording_sections(comparison)[0].tables


def test_a_noisier_sim_fails_sub_pixel_and_fill_in_every_bin(recordings: dict[str, Path]) -> None:
    """Three times the disparity noise, three times the holes: sub-pixel RMS and fill fail in both bins; plane-fit
    RMS (z^2 sigma_d / (f B), 0.2 -> 0.5 % at 0.6 m, 0.7 -> 2.2 % at 1.25 m) only beyond the 1-point limit."""
    profile = load_profile(PROFILE)
    comparison = compare_recordings(profile, profile, sim_source=str(recordings["noisy"]),
                                    real_source=f"left={recordings['real']}/left,depth={recordings['real']}/depth",
                                    pattern=(9, 6), square_m=0.08, preset="profile", tol=Tolerances(fill_gap=0.1))
    for row in comparison.rows:
        failed = {v["metric"] for v in row["verdicts"] if not v["passed"]}
        far = row["lo_m"] >= 1.0
        assert failed == {"subpixel_rms_px", "fill_rate_pct", *(["plane_fit_rms_pct"] if far else [])}, row["verdict"]
        sub = next(m for m in row["metrics"] if m["metric"] == "subpixel_rms_px")
        assert sub["gap"] == pytest.approx(0.2, rel=0.15) and sub["certain"]
        assert row["verdict"].startswith("FAIL")
    failing = [c for c in recording_checks(comparison) if not c.passed]
    assert len(failing) == 5 and all(c.section == "recording" for c in failing)


def test_recording_sources_are_parsed_and_bad_ones_named(tmp_path: Path, recordings: dict[str, Path]) -> None:
    assert not parse_source(str(recordings["real"])).stereo  # left/ + depth/: device depth
    src = parse_source("bag=run.bag,left-topic=/l,right-topic=/r,max-dt=0.02", option="--sim-recording")
    assert src.stereo and src.max_dt_s == 0.02 and src.bag == "run.bag"
    for text, words in [("left=a,colour=b", "key=value"), ("left=a", "exactly one depth source"),
                        ("left=a,right=b,depth=c", "exactly one"), ("left-topic=/l,depth=d", "bag"),
                        ("bag=x,right-topic=/r", "left-topic"), ("left=a,depth=b,depth-scale=-1", "positive"),
                        (str(tmp_path / "missing"), "not found")]:
        with pytest.raises(DepthError) as err:
            parse_source(text, option="--sim-recording")
        assert words in str(err.value) and "--sim-recording" in str(err.value)


def test_cli_refuses_a_sim_recording_alone(capsys: pytest.CaptureFixture[str], recordings: dict[str, Path]) -> None:
    assert main(["validate", PROFILE, PROFILE, "--roles-as-given", "--sim-recording", str(recordings["twin"])]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "--recording" in err and err.count("\n") == 1


@pytest.mark.slow
def test_cli_both_recordings(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rig = make_rig(name="small_rig", width=320, height=240, baseline_m=0.06)  # small: validate's renders stay quick
    path = dump_profile(rig, tmp_path / "rig.yaml")
    K = rig.left.K
    cam = Camera(float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]), 320, 240, 0.06)
    folders = []
    for side, seed in (("real", 4), ("sim", 5)):
        rng = np.random.default_rng(seed)
        folder = tmp_path / side
        (folder / "left").mkdir(parents=True)
        (folder / "depth").mkdir()
        for i, (d, yaw) in enumerate([(0.6, 15), (0.65, -10), (0.7, 5)]):
            f = render(cam, (9, 6), 0.03, d, yaw, 5, sigma_d_px=0.1, mismatch_share=0.05, hole_share=0.1, bias=0.0,
                       rng=rng, supersample=2)
            write_png16(str(folder / "left" / f"{i:03d}.png"), f.left)
            write_png16(str(folder / "depth" / f"{i:03d}.png"), f.depth_mm)
        folders.append(folder)
    code = main(["-q", "validate", str(path), str(path), "--roles-as-given", "--quick", "--jobs", "1",
                 "--distances", "0.8,1.5", "--recording", str(folders[0]),
                 "--sim-recording", str(folders[1]), "--pattern", "9x6", "--square", "0.03", "--json",
                 "--report", str(tmp_path / "rep")])
    data = json.loads(capsys.readouterr().out)
    rec = data["recording"]
    assert {"real", "sim", "rows"} <= set(rec) and rec["sim_mode"] == "recording"
    assert [r["real_frames"] for r in rec["rows"]] == [3] and all(r["passed"] for r in rec["rows"])
    assert not [c for c in data["checks"] if c["section"] == "recording" and not c["passed"]]
    assert code in (0, 1)  # the rendered stages judge the rig itself; the recordings agree
    assert "Recording: sim vs real" in (tmp_path / "rep" / "validation.html").read_text()


def test_device_depth_real_side_with_the_sim_rendered_at_its_poses(tmp_path: Path) -> None:
    from s2r.validate.recording.compare import compare_recording

    rig = make_rig(name="small_rig", width=320, height=240, baseline_m=0.06)
    K = rig.left.K
    cam = Camera(float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]), 320, 240, 0.06)
    rng = np.random.default_rng(6)
    (tmp_path / "left").mkdir()
    (tmp_path / "depth").mkdir()
    truth = []
    for i, (d, yaw) in enumerate([(0.5, 15), (0.6, -10)]):
        f = render(cam, (9, 6), 0.03, d, yaw, 5, sigma_d_px=0.1, mismatch_share=0.0, hole_share=0.1, bias=0.0,
                   rng=rng, supersample=2)
        write_png16(str(tmp_path / "left" / f"{i:03d}.png"), f.left)
        write_png16(str(tmp_path / "depth" / f"{i:03d}.png"), f.depth_mm)
        truth.append(float(np.median(f.truth_m[f.roi])))
    comparison = compare_recording(rig, rig, tmp_path, pattern=(9, 6), square_m=0.03, preset="profile",
                                   tol=Tolerances())
    assert comparison.sim_source is None and "device depth" in comparison.real.source
    real = [f.distance_m for f in comparison.real.frames]
    sim = [f.distance_m for f in comparison.sim.frames]  # the sim boards sit where the real ones were
    assert real == pytest.approx(truth, rel=0.01) and sim == pytest.approx(truth, rel=0.01)
    assert all(f.scored for f in comparison.sim.frames)
