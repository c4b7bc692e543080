"""A T265-like fisheye pair (too wide for one pinhole) through `s2r render boards` and `s2r validate`."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.cli import main
from s2r.formats.s2r_yaml import dump_profile
from tests.render._helpers import t265_rig

CHARUCO = ("target_type: charuco\nsquaresX: 7\nsquaresY: 5\nsquareLength: 0.04\nmarkerLength: 0.03\n"
           "dictionary: DICT_4X4_50\n")


def _run(argv: list[str]) -> tuple[int, str]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(["-q", *argv])
    return code, out.getvalue()


@pytest.mark.slow
def test_t265_like_pair_renders_and_passes_its_self_check(tmp_path: Path) -> None:
    profile = dump_profile(t265_rig(), tmp_path / "t265.yaml")
    (tmp_path / "charuco.yaml").write_text(CHARUCO)
    code, _ = _run(["render", "boards", str(profile), "-o", str(tmp_path / "boards"), "--views", "2",
                    "--supersample", "1", "--jobs", "1", "--target", str(tmp_path / "charuco.yaml")])
    assert code == 0
    for side in ("left", "right"):
        image = cv2.imread(str(tmp_path / "boards" / side / "00.png"), cv2.IMREAD_GRAYSCALE)
        assert image.shape == (800, 848) and image[0, 0] == 0 and image[400, 424] > 0  # image circle

    code, text = _run(["validate", str(profile), "--quick", "--json"])
    assert code == 0, text
    data = json.loads(text)
    rows = {r["name"]: r for r in data["recovery"]["profile"]["rows"]}
    for side in ("left", "right"):
        for key in ("fx", "fy"):
            row = rows[f"{side} {key}"]
            assert abs(row["recovered"] / row["declared"] - 1) < 0.002, row  # the bars
        for key in ("cx", "cy"):
            assert abs(rows[f"{side} {key}"]["error"]) < 1.0
    assert abs(rows["baseline"]["recovered"] / rows["baseline"]["declared"] - 1) < 0.003
    within = data["depth"]["profile"]["within_3m"]
    assert within["median_pct"] < 2.0 and within["fill_rate"] > 0.8
    assert np.isfinite(within["bias_pct"])
