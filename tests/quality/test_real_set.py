"""Real figures: OpenCV's stereo chessboard set through the pipeline, depth on the board against its PnP plane,
with a profile calibrated from the same set. The issue's bar: no printed plane-fit RMS above 100 %, no sub-pixel
RMS above 20 px; every frame scored on its inliers or not scored with a reason."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from s2r.cli import main
from tests.conftest import shared_data

#: The board of these sets (`calibrate` has no default board).
BOARD = ("--pattern", "9x6", "--square", "0.025")

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def real_profile(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    data = shared_data("opencv_stereo_chessboard")
    profile = tmp_path_factory.mktemp("real") / "real.yaml"
    assert main(["-q", "calibrate", str(data), "--pattern", "9x6", "--square", "0.025", "-o", str(profile),
                 "--jobs", "1", "--json"]) == 0
    return data, profile


def _quality(capsys: pytest.CaptureFixture[str], data: Path, profile: Path, which: str, *extra: str
             ) -> dict[str, Any]:
    capsys.readouterr()
    code = main(["-q", "depth-quality", str(profile), "--left", str(data / f"left{which}.jpg"), "--right",
                 str(data / f"right{which}.jpg"), "--pattern", "9x6", "--square", "0.025", *extra, "--json"])
    assert code == 0
    return json.loads(capsys.readouterr().out)  # type: ignore[no-any-return]


def test_every_frame_is_a_measurement_or_says_why(real_profile: tuple[Path, Path],
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    data, profile = real_profile
    out = _quality(capsys, data, profile, "*")
    frames = out["frames"]
    assert len(frames) == 13
    for f in frames:
        if f["scored"]:  # measured here: plane-fit RMS 0.48-0.72 %, sub-pixel 0.49-0.81 px, |Z accuracy| < 0.5 %
            assert f["plane_fit_rms_pct"] < 2.0 and f["subpixel_rms_px"] < 2.0 and abs(f["z_accuracy_pct"]) < 1.0
            assert f["not_scored"] == ""
        else:
            assert f["not_scored"] and f["plane_fit_rms_pct"] is None and f["subpixel_rms_px"] is None
            assert f["z_accuracy_pct"] is None
    scored = [f["image"] for f in frames if f["scored"]]
    assert len(scored) == 13  # 5 before issue 38: 8 boards are nearer than the 160-disparity matcher sees (0.27 m)
    widened = [f for f in frames if "disparity range widened to" in f["note"]]
    assert len(widened) == 8 and all("the matcher's 160 px sees from 0.270 m" in f["note"] for f in widened)
    for b in out["bins"]:
        assert b["plane_fit_rms_pct"] is None or b["plane_fit_rms_pct"] < 100.0
        assert b["subpixel_rms_px"] is None or b["subpixel_rms_px"] < 20.0
    assert out["verdict"]["level"] == "check" and "not scored" not in out["verdict"]["headline"]


def test_wider_matcher_scores_more_and_mismatches_are_counted(real_profile: tuple[Path, Path],
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    data, profile = real_profile
    frames = _quality(capsys, data, profile, "0[678]", "--num-disparities", "256")["frames"]
    assert [f["image"] for f in frames] == ["left06.jpg", "left07.jpg", "left08.jpg"]
    for f in frames:  # measured here: Z accuracy -0.04..0.18 %, plane-fit RMS 0.5-0.9 %, fill 53-84 %
        assert f["scored"] and 0.25 < f["distance_m"] < 0.45
        assert abs(f["z_accuracy_pct"]) < 1.0
        assert f["plane_fit_rms_pct"] < 2.0 and f["subpixel_rms_px"] < 2.0
        assert f["fill_rate_pct"] > 40.0
    # too few disparities: left08's board (median 0.30 m, tilted) has a near edge at 0.252 m that 160 px cannot
    # reach (0.270 m): that frame is matched again with 192 px, said in its note
    (frame,) = _quality(capsys, data, profile, "08", "--num-disparities", "160")["frames"]
    assert frame["scored"] and "disparity range widened to 192 px for this frame (the board from 0.252 m" in \
        frame["note"]
    # at 256 disparities left12's whole board is inside the range, but 13 % of it is matched a chessboard period
    # (two squares, about 100 px of disparity) off: counted as outliers, left out of the RMS, which stays a measurement
    (frame,) = _quality(capsys, data, profile, "12", "--num-disparities", "256")["frames"]
    assert frame["scored"] and frame["outlier_pct"] > 5.0 and "mismatches" in frame["note"]
    assert frame["plane_fit_rms_pct"] < 2.0 and frame["subpixel_rms_px"] < 2.0 and abs(frame["z_accuracy_pct"]) < 1.0
