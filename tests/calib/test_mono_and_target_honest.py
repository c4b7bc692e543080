"""`calibrate --mono` honest on independent known-answer views: a held-out error over 4 folds (checked against
plain OpenCV on the same corners), the jackknife std beside the covariance's, repeated views merged; the same
for one camera with a ``--target`` board or a fisheye lens (partial views)."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import cv2
import numpy as np
import pytest
import yaml
from numpy.typing import NDArray

from s2r.calib.detect import Detection
from s2r.calib.solve.pipelines.mono import MonoCalibration, calibrate_mono_detections
from s2r.calib.solve.pipelines.target_mono import calibrate_mono_target_detections
from s2r.calib.solve.pipelines.target_stereo import calibrate_stereo_target_detections
from s2r.targets import target_from_mapping
from tests import raycast as rc
from tests.calib.independent_rig import PATTERN, SIZE, SQUARE_M, board_points, make_rig

Array = NDArray[np.float64]


def _dets(views: list[Array]) -> list[Detection]:
    return [Detection(f"cam/{i:03d}", "", "ok", size=SIZE, corners=v.astype(np.float32)) for i, v in enumerate(views)]


def _calibrate(views: list[Array]) -> MonoCalibration:
    return calibrate_mono_detections(_dets(views), pattern=PATTERN, square_m=SQUARE_M, name="t", jobs=1,
                                     compare=False)


def _ratios(res: MonoCalibration) -> Array:
    """jackknife std / covariance std of fx, fy, cx, cy."""
    params = res.figures()["heldout"]["parameters"]
    return np.array([params[n]["std_jackknife"] / params[n]["std_covariance"] for n in ("fx", "fy", "cx", "cy")])


def _plain_heldout(views: list[Array], folds: int = 4) -> float:
    """Plain OpenCV: calibrateCamera from scratch on the views not in fold f (view i in fold i mod 4), each held-out
    view's pose by solvePnP + LM refinement with those intrinsics; RMS per corner (px)."""
    obj = board_points().astype(np.float32)
    pts = [v.astype(np.float32).reshape(-1, 1, 2) for v in views]
    sq = []
    for f in range(folds):
        test = set(range(f, len(pts), folds))
        train = [pts[i] for i in range(len(pts)) if i not in test]
        _, K, D, _, _ = cv2.calibrateCamera([obj] * len(train), train, SIZE, None, None, flags=cv2.CALIB_FIX_K3)
        for i in sorted(test):
            _, rv, tv = cv2.solvePnP(obj, pts[i], K, D)
            rv, tv = cv2.solvePnPRefineLM(obj, pts[i], K, D, rv, tv)
            proj = cv2.projectPoints(obj, rv, tv, K, D)[0].reshape(-1, 2)
            sq.append(np.sum((proj - pts[i].reshape(-1, 2)) ** 2, axis=1))
    return float(np.sqrt(np.mean(np.concatenate(sq))))


def test_heldout_error_matches_plain_opencv_and_drives_the_verdict() -> None:
    rig = make_rig(41, views=16, noise_px=0.1, k3_max=0.0)
    res = _calibrate(rig.left)
    held = res.figures()["heldout"]
    plain = _plain_heldout(rig.left)
    assert held["folds"] == 4 and not held["failed_folds"] and held["corners_total"] == 16 * 54
    assert abs(held["heldout_px"] / plain - 1) < 0.10
    # noise of 0.1 px per coordinate: about 0.14 px per corner
    assert 0.12 < held["heldout_px"] < 0.16 and held["heldout_px"] <= held["heldout_all_px"]
    assert res.verdict is not None
    assert any(r.text.startswith(f"held-out error {held['heldout_px']:.3f} px") for r in res.verdict.reasons)
    assert res.figures()["board"] == "chessboard 9x6 inner corners, 25 mm squares"
    maps = res.figures()["projection_uncertainty"]["camera"]
    for src in ("covariance", "jackknife"):  # the centre is known better than the corners
        assert maps[src]["source"] == src and 0 < maps[src]["centre_px"] < maps[src]["corner_px"] < 3.0


def test_both_std_reported_the_larger_and_about_equal_on_a_clean_set() -> None:
    pooled = []
    for seed in (45, 46, 47):
        rig = make_rig(seed, views=16, noise_px=0.1, k3_max=0.0)
        res = _calibrate(rig.left)
        params = res.figures()["heldout"]["parameters"]
        std = res.profile.camera.std
        assert std is not None
        for name, got in (("fx", std.fx_px), ("fy", std.fy_px), ("cx", std.cx_px), ("cy", std.cy_px)):
            p = params[name]
            assert got == p["std"] == max(p["std_covariance"], p["std_jackknife"]), name
            assert p["std_source"] == ("jackknife" if p["std_jackknife"] > p["std_covariance"] else "covariance")
        lens = rig.left_lens
        assert abs(res.profile.camera.fx_px - lens.fx) <= 4 * params["fx"]["std"]
        assert abs(res.profile.camera.cx_px - lens.cx) <= 4 * params["cx"]["std"]
        pooled.append(_ratios(res))
    # noise only: 4 folds estimate the same spread as the covariance (a rough estimate, so pooled over 3 sets)
    assert 0.6 < float(np.exp(np.mean(np.log(pooled)))) < 1.6


def test_jackknife_exceeds_the_covariance_with_a_bent_board() -> None:
    """A board bent by 1 mm (not in the model): the views disagree by more than the noise explains."""
    for seed in (31, 32):
        rig = make_rig(seed, views=16, noise_px=0.05, k3_max=0.0, bend_m=(0.001, 0.0007))
        res = _calibrate(rig.left)
        ratios = _ratios(res)
        assert float(np.exp(np.mean(np.log(ratios)))) > 1.8, ratios
        params = res.figures()["heldout"]["parameters"]
        assert sum(p["std_source"] == "jackknife" for p in params.values()) >= 3


def test_every_view_three_times_keeps_the_std() -> None:
    """A still board: each view repeated exactly and with 0.01 px jitter is merged, and the std does not shrink."""
    rig = make_rig(47, views=12, noise_px=0.1, k3_max=0.0)
    rng = np.random.default_rng(5)
    tripled = [c for v in rig.left for c in (v, v, v + rng.normal(0.0, 0.01, v.shape))]
    one, three = _calibrate(rig.left), _calibrate(tripled)
    repeats = [d for d in three.dropped if d.reason.startswith("repeat of")]
    assert len(repeats) == 24 and len(three.view_names) == len(one.view_names) == 12
    assert any("repeat an earlier view" in w for w in three.warnings)
    a, b = one.profile.camera.std, three.profile.camera.std
    assert a is not None and b is not None
    for name in ("fx_px", "fy_px", "cx_px", "cy_px"):
        assert abs(getattr(b, name) / getattr(a, name) - 1) < 0.15, name


def _target_pairs(kind: str, views: int, seed: int) -> tuple[list[tuple[str, Detection, Detection]], Any, Any]:
    """Corner detections with ids of both cameras of tests/raycast.py's independent rigs, noise 0.1 px per
    coordinate (a ChArUco board's views cut by the image edge are partial; a chessboard cut is not found, as a
    detector finds it): the pairs, the s2r target and the rig."""
    rig = rc.fisheye_rig(rc.chessboard_target((8, 6), 0.03, 48), "f", 0.6) if kind == "fisheye" else \
        rc.pinhole_rig(rc.charuco_target((9, 7), 0.035, 0.026, "DICT_4X4_50", 60), "c", 0.75)
    tg = rig.target
    rng = np.random.default_rng(seed)
    pairs = []
    for k, (R, t, _cut) in enumerate(rc.sample_poses(rig, views, seed=seed)):
        X = tg.points @ R.T + t
        dets = []
        for side, lens, pts in (("left", rig.left, X), ("right", rig.right, X @ rig.R.T + rig.T)):
            seen = rc._visible(lens, pts)
            size = (lens.width, lens.height)
            if kind == "fisheye" and not seen.all():
                dets.append(Detection(f"{side}/{k:02d}", "", "no_board", size=size))
                continue
            uv = lens.project(pts[seen]) + rng.normal(0.0, 0.1, (int(seen.sum()), 2))
            dets.append(Detection(f"{side}/{k:02d}", "", "ok", size=size, corners=uv.astype(np.float32),
                                  ids=tg.ids[seen].astype(np.int32)))
        pairs.append((f"{k:02d}", dets[0], dets[1]))
    return pairs, target_from_mapping(yaml.safe_load(tg.yaml)), rig


def _target_views(kind: str, views: int, seed: int) -> tuple[list[Detection], Any, Any]:
    """The left camera's detections of :func:`_target_pairs`, the target and the left lens."""
    pairs, target, rig = _target_pairs(kind, views, seed)
    return [a for _, a, _ in pairs], target, rig.left


@pytest.mark.parametrize("kind", ["fisheye", "charuco"])
def test_target_and_fisheye_mono_have_a_heldout_error_and_both_std(kind: str) -> None:
    dets, target, lens = _target_views(kind, 16, 4)
    if kind == "charuco":
        assert any(len(d.corners) < target.corner_count for d in dets if d.corners is not None)  # partial views
    res = calibrate_mono_target_detections(dets, target=target, lens="fisheye" if kind == "fisheye" else "pinhole")
    fig = res.figures()
    held = fig["heldout"]
    assert held["folds"] == 4 and not held["failed_folds"]
    assert 0.12 < held["heldout_px"] < 0.16  # 0.1 px per coordinate
    std = res.profile.camera.std
    assert std is not None and fig["board"] == target.describe()
    for name, true in (("fx", lens.fx), ("fy", lens.fy), ("cx", lens.cx), ("cy", lens.cy)):
        p = held["parameters"][name]
        assert p["std"] == max(p["std_covariance"], p["std_jackknife"]) == getattr(std, f"{name}_px")
        assert abs(p["value"] - true) <= 4 * p["std"], name
    assert res.verdict is not None and any(r.text.startswith("held-out error") for r in res.verdict.reasons)


def test_target_mono_merges_repeated_views() -> None:
    dets, target, _ = _target_views("charuco", 10, 6)
    tripled = [replace(d, name=f"{d.name}-{k}") for d in dets for k in range(3)]
    one = calibrate_mono_target_detections(dets, target=target)
    three = calibrate_mono_target_detections(tripled, target=target)
    assert sum(d.reason.startswith("repeat of") for d in three.dropped) == 20
    assert any("repeat an earlier view" in w for w in three.warnings)
    a, b = one.profile.camera.std, three.profile.camera.std
    assert a is not None and b is not None
    for name in ("fx_px", "fy_px", "cx_px", "cy_px"):
        assert abs(getattr(b, name) / getattr(a, name) - 1) < 0.15, name


@pytest.mark.parametrize("kind", ["fisheye", "charuco"])
def test_target_pair_has_a_stereo_heldout_error_both_std_and_merges_repeats(kind: str) -> None:
    pairs, target, rig = _target_pairs(kind, 14, 4)
    lens = "fisheye" if kind == "fisheye" else "pinhole"
    res = calibrate_stereo_target_detections(pairs, target=target, lens=lens)
    held = res.figures()["stereo_heldout"]
    assert held is not None and held["folds"] == 4 and not held["failed_folds"]
    assert 0.12 < held["heldout_px"] < 0.17  # 0.1 px per coordinate
    params = held["parameters"]
    for name, p in params.items():
        assert p["std"] == max(p["std_covariance"], p["std_jackknife"]), name
    assert res.profile.extrinsics.baseline_std_m == params["baseline"]["std"]
    assert abs(res.profile.baseline_m - float(np.linalg.norm(rig.T))) <= 4 * params["baseline"]["std"]
    assert abs(res.profile.left.fx_px - rig.left.fx) <= 4 * params["left fx"]["std"]
    assert res.verdict is not None and any("held-out error" in r.text for r in res.verdict.reasons)
    tripled = [(f"{n}-{k}", replace(a, name=f"{a.name}-{k}"), replace(b, name=f"{b.name}-{k}"))
               for n, a, b in pairs for k in range(3)]
    three = calibrate_stereo_target_detections(tripled, target=target, lens=lens)
    seen = sum(a.status == "ok" or b.status == "ok" for _, a, b in pairs)
    assert sum(d.reason.startswith("repeat of") for d in three.dropped) == 2 * seen
    assert any("repeat an earlier view" in w for w in three.warnings)
    sa, sb = res.profile.extrinsics.baseline_std_m, three.profile.extrinsics.baseline_std_m
    assert sa and sb and abs(sb / sa - 1) < 0.15


@pytest.mark.parametrize("kind", ["fisheye", "charuco"])
def test_target_pair_with_fixed_intrinsics_has_a_verdict(kind: str) -> None:
    """ROS's way (--fix-intrinsics) on a --target is judged too: the verdict names the stereo RMS, the epipolar
    error and the baseline's std (there is no held-out error on this path); it used to carry no verdict at all."""
    pairs, target, _ = _target_pairs(kind, 14, 4)
    res = calibrate_stereo_target_detections(pairs, target=target, lens="fisheye" if kind == "fisheye" else "pinhole",
                                             fix_intrinsics=True)
    assert res.verdict is not None
    levels = {r.text.split(" ")[0] + " " + r.text.split(" ")[1]: r.level for r in res.verdict.reasons}
    assert levels["stereo RMS"] == levels["epipolar RMS"] == "good", res.verdict
    assert any(k.startswith("baseline") and v == "good" for k, v in levels.items()), res.verdict
    assert not any("held-out" in r.text for r in res.verdict.reasons)
    assert res.figures()["verdict"]["level"] == res.verdict.level  # the --json and the console carry it


def test_lens_models_compared_on_the_same_folds_flag_a_missing_k3() -> None:
    """A lens with k3 = 0.2 (not in the default k1k2p1p2): plumb_bob's held-out error is clearly lower."""
    rig = make_rig(32, views=16, noise_px=0.05, k3_max=0.3)
    res = calibrate_mono_detections(_dets(rig.left), pattern=PATTERN, square_m=SQUARE_M, name="t", jobs=1)
    assert res.models is not None and res.heldout is not None
    scores = {s.model: s for s in res.models.scores}
    assert set(scores) == {"k1k2p1p2", "k1k2", "plumb_bob", "rational"}
    assert scores["k1k2p1p2"].heldout_px == pytest.approx(res.heldout.heldout_px)  # the same folds
    assert res.models.best == "plumb_bob" and res.models.warning and "--distortion plumb_bob" in res.models.warning
    assert res.verdict is not None and res.verdict.level != "good"
