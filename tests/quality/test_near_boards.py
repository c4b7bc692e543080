"""depth-quality scores boards nearer than the matcher sees (issue 38): the frame is matched again with a range
that reaches the board's nearest part (a multiple of 16, 5 % margin), said in its note; refused only when no range
the matcher supports (min_disparity + num_disparities under the image width) reaches it."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.quality.run import DepthView, widened_range
from tests.conftest import shared_data


def _view(width: int, low: int = 0) -> DepthView:
    depth = np.full((10, width), np.nan, np.float32)
    return DepthView("v", None, depth, np.eye(3), np.zeros(5), disparity_range=(low, 64),
                     rematch=lambda nd: _view(width, low))


def test_the_widened_range_is_hand_computed() -> None:
    # f B = 40 px m, board from 0.25 m: 40 / (0.95 * 0.25) + 1 = 169.4 px -> 176 (multiple of 16)
    assert widened_range(_view(640), 0.25, 40.0) == 176
    assert widened_range(_view(640, low=16), 0.25, 40.0) == 160  # min_disparity counts towards the reach
    assert widened_range(_view(176), 0.25, 40.0) is None  # 0 + 176 does not fit a 176 px image
    assert widened_range(DepthView("v", None, np.zeros((2, 640), np.float32), np.eye(3), np.zeros(5)),
                         0.25, 40.0) is None  # device depth cannot be matched again


def test_near_boards_of_a_real_set_are_scored_with_the_range_said(tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    data = shared_data("opencv_stereo_chessboard")
    profile = tmp_path / "real.yaml"
    assert main(["-q", "calibrate", str(data), "--pattern", "9x6", "--square", "0.025", "-o", str(profile),
                 "--jobs", "1", "--json"]) == 0
    capsys.readouterr()
    assert main(["-q", "depth-quality", str(profile), "--left", str(data / "left0[67].jpg"), "--right",
                 str(data / "right0[67].jpg"), "--pattern", "9x6", "--square", "0.025", "--num-disparities", "64",
                 "--json"]) == 0
    frames = json.loads(capsys.readouterr().out)["frames"]
    # a 64 px range sees from 0.68 m; both boards are at 0.33-0.40 m: each is matched again and scored
    for f in frames:
        assert f["scored"], f["not_scored"]
        assert "disparity range widened to" in f["note"] and "the matcher's 64 px sees from" in f["note"]
