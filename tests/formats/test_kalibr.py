"""Kalibr camchain: round trips, the T_cn_cnm1 convention, k3 refusal."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest
import yaml

from s2r.errors import FormatError
from s2r.formats.kalibr import dump_kalibr, kalibr_to_yaml, load_kalibr
from tests.conftest import make_rig
from tests.formats.rigs import assert_same_rig, distorted_rotated_rig, with_distortion


def test_round_trip_radtan(tmp_path: Path) -> None:
    rig = with_distortion(distorted_rotated_rig(), "plumb_bob", (-0.12, 0.05, 0.001, -0.002, 0.0))
    back = load_kalibr(dump_kalibr(rig, tmp_path / "camchain.yaml"))
    assert_same_rig(back, rig, tol=1e-12)
    assert back.provenance.method == "imported from Kalibr camchain"


def test_round_trip_equidistant(tmp_path: Path) -> None:
    rig = with_distortion(make_rig(rotation_deg=(-0.4, 0.7, 0.1)), "equidistant", (0.05, -0.01, 0.002, -0.0005))
    assert_same_rig(load_kalibr(dump_kalibr(rig, tmp_path / "camchain.yaml")), rig, tol=1e-12)


def test_layout_and_convention_by_hand() -> None:
    """Right camera 0.1 m to the right: T_cn_cnm1 maps cam0 points into cam1, so its translation is -0.1 m."""
    data = yaml.safe_load(kalibr_to_yaml(make_rig(baseline_m=0.1)))
    cam0, cam1 = data["cam0"], data["cam1"]
    fx = make_rig().left.fx_px
    assert cam0["camera_model"] == "pinhole" and cam0["distortion_model"] == "radtan"
    assert cam0["intrinsics"] == [fx, fx, 319.5, 239.5] and cam0["resolution"] == [640, 480]
    assert cam0["distortion_coeffs"] == [0.0, 0.0, 0.0, 0.0]
    np.testing.assert_allclose(cam1["T_cn_cnm1"], [[1, 0, 0, -0.1], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
                               atol=1e-15)
    # a point 1 m ahead of cam0 sits 0.1 m to the LEFT (x = -0.1) of cam1
    point_cam1 = np.asarray(cam1["T_cn_cnm1"]) @ np.array([0.0, 0.0, 1.0, 1.0])
    np.testing.assert_allclose(point_cam1[:3], [-0.1, 0.0, 1.0], atol=1e-15)


def test_k3_is_refused_or_dropped_with_a_warning(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    rig = distorted_rotated_rig()  # k3 = 0.01
    with pytest.raises(FormatError, match=r"left\.distortion: k3 = 0\.01 cannot be written.*--drop-k3"):
        dump_kalibr(rig, tmp_path / "c.yaml")
    assert not (tmp_path / "c.yaml").exists()
    with caplog.at_level(logging.WARNING, logger="s2r"):
        back = load_kalibr(dump_kalibr(rig, tmp_path / "c.yaml", drop_k3=True))
    assert "dropping k3" in caplog.text
    assert back.left.D.tolist() == [-0.12, 0.05, 0.001, -0.002, 0.0]


def test_rational_model_has_no_kalibr_equivalent(tmp_path: Path) -> None:
    rig = with_distortion(make_rig(), "rational_polynomial", (0.0,) * 8)
    with pytest.raises(FormatError, match="rational_polynomial has no Kalibr equivalent"):
        dump_kalibr(rig, tmp_path / "c.yaml")


def test_real_kalibr_extra_fields_are_tolerated(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    data = yaml.safe_load(kalibr_to_yaml(make_rig()))
    data["cam0"]["T_cam_imu"] = np.eye(4).tolist()
    data["cam0"]["timeshift_cam_imu"] = 0.003
    data["cam1"]["intrinsic_extra"] = 1
    path = tmp_path / "camchain-imucam.yaml"
    path.write_text(yaml.safe_dump(data))
    with caplog.at_level(logging.WARNING, logger="s2r"):
        assert load_kalibr(path).baseline_m == pytest.approx(0.1)
    assert "cam1: ignoring unknown Kalibr fields intrinsic_extra" in caplog.text
