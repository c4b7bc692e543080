"""Known answers from an independent generator (tests/raycast.py: own lens maths, boards drawn by cv2.aruco
and Kalibr's layout, about 40 % of the views cut by the image edge), recovered by s2r's target calibration.

Small, fast rigs (12 views at reduced resolution); the full-size bars are measured by bench/bench_targets.py.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from s2r.calib.solve.pipelines.target_stereo import calibrate_stereo_target
from s2r.cli import main
from s2r.formats.s2r_yaml import load_profile_file
from s2r.targets import target_from_mapping
from tests import raycast as rc

RIGS = {
    "charuco_pinhole": lambda: rc.pinhole_rig(rc.charuco_target((9, 7), 0.035, 0.026, "DICT_4X4_50", 60), "c", 0.75),
    "aprilgrid_pinhole": lambda: rc.pinhole_rig(rc.aprilgrid_target((5, 4), 0.045, 0.3, 60), "a", 0.75),
    "chess_fisheye": lambda: rc.fisheye_rig(rc.chessboard_target((8, 6), 0.03, 48), "f", 0.6),
}


@pytest.mark.slow
@pytest.mark.parametrize("kind", list(RIGS))
def test_independent_rig_recovered(kind: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr(rc, "SUB", 2)  # 2x2 samples per pixel: enough here, and twice as fast
    rig = RIGS[kind]()
    truth = rc.write_rig(rig, tmp_path, views=12, seed=5)
    assert truth["cut"] >= 4  # views cut by the image edge are part of the set
    target = target_from_mapping(yaml.safe_load((tmp_path / "target.yaml").read_text()))
    lens = "fisheye" if "fisheye" in kind else "pinhole"
    if kind == "chess_fisheye":  # through the CLI: a --pattern chessboard with --lens fisheye, and the report
        out = tmp_path / "rig.yaml"
        code = main(["calibrate", str(tmp_path), "--pattern", "8x6", "--square", "0.03", "--lens", "fisheye", "-o",
                     str(out), "--report", str(tmp_path / "report"), "--jobs", "1"])
        assert code == 0, capsys.readouterr().err
        assert "right k4" in (tmp_path / "report" / "index.html").read_text()  # the equidistant terms
        p = load_profile_file(out)
    else:
        res = calibrate_stereo_target(sorted((tmp_path / "left").glob("*.png")),
                                      sorted((tmp_path / "right").glob("*.png")), target=target, lens=lens, jobs=1)
        p = res.profile
        assert any(len(c) < target.corner_count for c in res.corners_left)  # partial views were used
    for cam, true in ((p.left, rig.left), (p.right, rig.right)):
        assert cam.distortion.model == ("equidistant" if lens == "fisheye" else "plumb_bob")
        assert cam.fx_px == pytest.approx(true.fx, rel=0.004)
        assert cam.fy_px == pytest.approx(true.fy, rel=0.004)
        assert abs(cam.cx_px - true.cx) < 1.5 and abs(cam.cy_px - true.cy) < 1.5
    assert p.baseline_m == pytest.approx(float(np.linalg.norm(rig.T)), rel=0.005)
    assert p.extrinsics.baseline_std_m is not None and p.extrinsics.baseline_std_m > 0
