"""Known answer from rendered images: chessboards ray-cast through a random plumb_bob rig (tests/calib/image_rig.py,
no s2r code), calibrated by ``s2r calibrate`` with default flags. Corner detection is part of what is checked.

One seeded 640x480 rig with 20 views, as the issue's rigs (the bench bench/bench_calib_images.py measures
14). Measured when the test was written: s2r's corners 0.03 px RMS from the truth, plain OpenCV's
(cornerSubPix 11x11, the sample's window) several px on small squares; focal error at most 0.026 %, principal
point 0.12 px, baseline 0.049 % (this rig is the unlucky one: 2.4 reported sigma; the bench's worst over 14
rigs is 0.024 %), every error within 3 reported sigma.
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.calib.detect import detect_board
from s2r.cli import main
from s2r.formats.s2r_yaml import load_profile_file
from tests.calib.image_rig import PATTERN, ImageRig, render_rig, sigma_ratios

#: The board of these sets (`calibrate` has no default board).
BOARD = ("--pattern", "9x6", "--square", "0.025")

pytestmark = pytest.mark.slow  # renders 40 images (about 20 s on an idle core)
SEED = 11
VIEWS = 20


@pytest.fixture(scope="module")
def image_rig(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, ImageRig]:
    folder = tmp_path_factory.mktemp("image_rig") / "rig"
    return folder, render_rig(SEED, folder, views=VIEWS)


def _matched(found: np.ndarray, true: np.ndarray) -> np.ndarray:
    """Detected corners minus the truth, in whichever of the two orders OpenCV reported them."""
    direct, flipped = found - true, found - true[::-1]
    return direct if np.abs(direct).max() < np.abs(flipped).max() else flipped


def test_s2r_corners_are_subpixel_accurate_and_beat_the_plain_sample_window(image_rig: tuple[Path, ImageRig]) -> None:
    folder, truth = image_rig
    ours, plain = [], []
    crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.001)
    for k, pair in enumerate(truth.corners):
        for side, true in zip(("left", "right"), pair, strict=True):
            gray = cv2.imread(str(folder / side / f"{k:02d}.png"), cv2.IMREAD_GRAYSCALE)
            found, _ = detect_board(gray, PATTERN)
            assert found is not None, f"{side}/{k:02d}.png: no board found"
            ours.append(_matched(found.astype(np.float64), true))
            ok, c = cv2.findChessboardCorners(gray, PATTERN, flags=cv2.CALIB_CB_ADAPTIVE_THRESH
                                              | cv2.CALIB_CB_NORMALIZE_IMAGE)
            if ok:
                c = cv2.cornerSubPix(gray, c, (11, 11), (-1, -1), crit).reshape(-1, 2)
                plain.append(_matched(c.astype(np.float64), true))
    err = np.concatenate(ours)
    rms = float(np.sqrt(np.mean(err ** 2)))
    assert rms < 0.05 and float(np.abs(err).max()) < 0.25  # measured: 0.03 px RMS
    assert np.all(np.abs(err.mean(axis=0)) < 0.01)  # no bias
    assert plain and rms < float(np.sqrt(np.mean(np.concatenate(plain) ** 2)))


def test_default_calibration_meets_the_issue_bars_with_honest_sigma(image_rig: tuple[Path, ImageRig], tmp_path: Path,
                                                                    capsys: pytest.CaptureFixture[str]) -> None:
    folder, truth = image_rig
    out = tmp_path / "rig.yaml"
    assert main(["calibrate", *BOARD, str(folder), "-o", str(out), "--json", "--jobs", "1", "--no-cache"]) == 0
    figures = json.loads(capsys.readouterr().out)
    p = load_profile_file(out)
    q = p.provenance.calibration
    assert q is not None and q.views_used == VIEWS and q.distortion_terms == "k1k2p1p2"
    cams = [(c.fx_px, c.fy_px, c.cx_px, c.cy_px) for c in (p.left, p.right)]
    ref = [(truth.left.fx, truth.left.fy, truth.left.cx, truth.left.cy),
           (truth.right.fx, truth.right.fy, truth.right.cx, truth.right.cy)]
    focal = [100 * abs(c[k] - t[k]) / t[k] for c, t in zip(cams, ref, strict=True) for k in (0, 1)]
    pp = [abs(c[k] - t[k]) for c, t in zip(cams, ref, strict=True) for k in (2, 3)]
    baseline = 100 * abs(p.baseline_m - truth.baseline_m) / truth.baseline_m
    # the issue's bars: worst focal 0.12 %, principal point 0.6 px, baseline 0.05 %. This rig's baseline sits at
    # 0.049 % (2.4 sigma) with OpenCV 5.0; a single rig under another OpenCV build may land just past the bar, so
    # the baseline gets 20 % room here and the bar itself is measured over 14-32 rigs by bench_calib_images.py.
    assert max(focal) <= 0.12 and max(pp) <= 0.6 and baseline <= 0.06, (focal, pp, baseline)
    stds = [(c.std.fx_px, c.std.fy_px, c.std.cx_px, c.std.cy_px) for c in (p.left, p.right)  # type: ignore[union-attr]
            ]
    z = sigma_ratios(truth, cams, stds, p.baseline_m, p.extrinsics.baseline_std_m)
    assert max(z) <= 3.0, z  # every error within 3 reported sigma
    # the right camera is rotated by the truth's angle, within its reported std
    angle = np.degrees(np.linalg.norm(cv2.Rodrigues(p.R @ truth.R.T)[0]))
    assert figures["rotation_std_deg"] is not None and angle <= 3 * figures["rotation_std_deg"]
    assert figures["verdict"]["level"] in ("good", "check") and figures["model_comparison"]["best"]
