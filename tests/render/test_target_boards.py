"""`render boards --target`: ChArUco and Kalibr AprilGrid sets whose truth (in the target's frame) matches what
cv2.aruco detects, with views cut by the image edge."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from s2r.calib.detect.markers import detect_target
from s2r.cli import main
from s2r.lens.distortion import project_points
from s2r.render import render_board_set
from s2r.targets import target_from_mapping
from tests.conftest import make_rig

CHARUCO = {"target_type": "charuco", "squaresX": 7, "squaresY": 5, "squareLength": 0.03, "markerLength": 0.022,
           "dictionary": "DICT_4X4_50"}
APRILGRID = {"target_type": "aprilgrid", "tagCols": 5, "tagRows": 4, "tagSize": 0.03, "tagSpacing": 0.3}


@pytest.mark.parametrize("spec", [CHARUCO, APRILGRID], ids=["charuco", "aprilgrid"])
def test_rendered_target_matches_its_truth(tmp_path: Path, spec: dict[str, object]) -> None:
    rig = make_rig(distortion=(-0.1, 0.02, 0.0, 0.0, 0.0))
    target = target_from_mapping(spec)
    result = render_board_set(rig, tmp_path, views=5, seed=2, jobs=1, target=target, cut_share=0.4)
    truth = yaml.safe_load(result.truth_path.read_text())
    assert truth["target"]["target_type"] == spec["target_type"] and len(truth["views_cut_by_edge"]) == 2
    seen = []
    for k, T in enumerate(result.poses):
        found, _ = detect_target(cv2.imread(str(result.left_paths[k]), cv2.IMREAD_GRAYSCALE), target)
        if found is None:  # a far, steep view whose small tags do not decode
            continue
        ids, pts = found
        expected = project_points(rig.left, target.points_of(ids) @ T[:3, :3].T + T[:3, 3])
        assert float(np.median(np.linalg.norm(pts - expected, axis=1))) < 0.3
        seen.append(len(ids) / target.corner_count)
    assert len(seen) >= 4 and min(seen) < 0.85  # the cut views lose corners to the edge


def test_render_cli_target_and_bad_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump({**CHARUCO, "dictionary": "DICT_NOPE"}))
    code = main(["render", "boards", "gazebo_dual_camera", "--target", str(bad), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and "dictionary" in err and len(err.strip().splitlines()) == 1
