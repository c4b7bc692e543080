"""s2r.compat.camera_configs: the seed tutorial's names, equal to OpenCV called by hand; S2R_PROFILE swapping."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import cv2
import numpy as np
import pytest

from s2r.compat import CAMERA_CONFIG_NAMES
from s2r.depth.pipeline import StereoPipeline
from s2r.errors import ProfileError
from s2r.formats.s2r_yaml import dump_profile
from s2r.profile import StereoProfile
from tests.conftest import make_rig
from tests.depth.synth import make_pair

MODULE = "s2r.compat.camera_configs"


@pytest.fixture
def fresh_import() -> Iterator[None]:
    sys.modules.pop(MODULE, None)
    yield
    sys.modules.pop(MODULE, None)


def _import() -> ModuleType:
    sys.modules.pop(MODULE, None)
    return importlib.import_module(MODULE)


def test_names_and_values_match_opencv_by_hand(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                              distorted_rig: StereoProfile, fresh_import: None) -> None:
    monkeypatch.setenv("S2R_PROFILE", str(dump_profile(distorted_rig, tmp_path / "distorted_rig.yaml")))
    cc = _import()
    for name in CAMERA_CONFIG_NAMES:
        assert hasattr(cc, name), name
    # What the seed's camera_configs.py does, by hand:
    K1 = np.array([[distorted_rig.left.fx_px, 0, 322.0], [0, distorted_rig.left.fy_px, 238.5], [0, 0, 1]])
    D1 = np.array([[-0.12, 0.05, 0.0, 0.0, 0.0]])
    T = -np.asarray(cc.R) @ np.array([0.1, 0.0, 0.0])
    size = (640, 480)
    R1, R2, P1, P2, Q, _, _ = cv2.stereoRectify(K1, D1, K1, D1, size, cc.R, T.reshape(3, 1))
    lm1, lm2 = cv2.initUndistortRectifyMap(K1, D1, R1, P1, size, cv2.CV_16SC2)
    rm1, rm2 = cv2.initUndistortRectifyMap(K1, D1, R2, P2, size, cv2.CV_16SC2)
    np.testing.assert_allclose(cc.left_camera_matrix, K1)
    np.testing.assert_allclose(cc.right_camera_matrix, K1)
    np.testing.assert_allclose(cc.left_distortion, D1)
    np.testing.assert_allclose(cc.right_distortion, D1)
    np.testing.assert_allclose(cc.T, T, atol=1e-12)
    assert cc.size == size
    for mine, theirs in ((cc.R1, R1), (cc.R2, R2), (cc.P1, P1), (cc.P2, P2), (cc.Q, Q)):
        np.testing.assert_allclose(mine, theirs, rtol=1e-12, atol=1e-9)
    for mine, theirs in ((cc.left_map1, lm1), (cc.left_map2, lm2), (cc.right_map1, rm1), (cc.right_map2, rm2)):
        assert mine.dtype == theirs.dtype and mine.shape == theirs.shape
        np.testing.assert_array_equal(mine, theirs)
    assert cc.profile.name == "distorted_rig"


def test_import_without_s2r_profile_names_the_variable(monkeypatch: pytest.MonkeyPatch, fresh_import: None
                                                       ) -> None:
    monkeypatch.delenv("S2R_PROFILE", raising=False)
    with pytest.raises(ProfileError, match=r"^S2R_PROFILE: .*needs a profile \(set S2R_PROFILE"):
        _import()


def test_unknown_profile_name(monkeypatch: pytest.MonkeyPatch, fresh_import: None) -> None:
    monkeypatch.setenv("S2R_PROFILE", "no_such_profile")
    with pytest.raises(ProfileError, match="unknown profile name 'no_such_profile'"):
        _import()


def _downstream_script() -> float:
    """Downstream code that names no profile: the median depth of the synthetic box."""
    pair = make_pair(width=640, height=480, d_box=40, d_background=20)
    result = StereoPipeline(preset="fast").compute(pair.left, pair.right)
    x0, x1, y0, y1 = pair.box
    return float(np.nanmedian(result.depth[y0 + 8:y1 - 8, x0 + 8:x1 - 8]))


def test_s2r_profile_swaps_the_profile(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fresh_import: None) -> None:
    wide = make_rig(name="sim_rig", baseline_m=0.1)
    narrow = make_rig(name="real_rig", baseline_m=0.05)
    for rig in (wide, narrow):
        dump_profile(rig, tmp_path / f"{rig.name}.yaml")
    monkeypatch.setenv("S2R_PROFILE_PATH", str(tmp_path))
    depths = {}
    for rig in (wide, narrow):
        monkeypatch.setenv("S2R_PROFILE", rig.name)
        depths[rig.name] = _downstream_script()
        assert _import().profile.name == rig.name
        assert _import().P2[0, 3] == pytest.approx(-rig.left.fx_px * rig.baseline_m)
    fx = wide.left.fx_px
    assert depths["sim_rig"] == pytest.approx(fx * 0.1 / 40, rel=2e-3)
    assert depths["real_rig"] == pytest.approx(fx * 0.05 / 40, rel=2e-3)
