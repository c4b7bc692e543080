"""profile convert, third round: --swap and one layout rule with from-urdf, the format it logs for an s2r profile,
camera files without stereo extrinsics, and a T in millimetres naming --units-m."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.formats.detect import load_any
from s2r.formats.ros import dump_ros_pair
from tests.conftest import make_rig

MAT = "!!opencv-matrix\n   rows: {r}\n   cols: {c}\n   dt: d\n   data: [{d}]\n"



def _opencv(path: Path, T: str) -> Path:
    path.write_text("%YAML:1.0\nimage_width: 640\nimage_height: 480\n"
                    f"M1: {MAT.format(r=3, c=3, d='536.07, 0, 342.37, 0, 536.01, 235.53, 0, 0, 1')}"
                    f"D1: {MAT.format(r=1, c=5, d='-0.26, 0.05, 0, 0, 0')}"
                    f"M2: {MAT.format(r=3, c=3, d='542.34, 0, 326.41, 0, 541.94, 249.87, 0, 0, 1')}"
                    f"D2: {MAT.format(r=1, c=5, d='-0.27, 0.06, 0, 0, 0')}"
                    f"R: {MAT.format(r=3, c=3, d='1, 0, 0, 0, 1, 0, 0, 0, 1')}"
                    f"T: {MAT.format(r=3, c=1, d=T)}")
    return path


def test_right_camera_on_the_left_is_refused_then_swapped(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """T = (+0.0836, 0, 0): X_right = X_left + T puts the 'right' camera 8.36 cm to the LEFT (from-urdf refuses
    the same layout with [baseline-side], tests/sources/test_real_descriptions.py)."""
    src = _opencv(tmp_path / "swapped.yml", "0.0836, 0.001, 0.0")
    out = tmp_path / "rig.yaml"
    assert main(["profile", "convert", str(src), "--to", "s2r", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "extrinsics: [baseline-side] the 'right' camera is 8.4 cm to the LEFT" in err
    assert "--swap" in err and "--allow-bad-baseline" in err and not out.exists()
    assert main(["profile", "convert", str(src), "--to", "s2r", "-o", str(out), "--swap"]) == 0
    p = load_any(out)
    assert (p.left.fx_px, p.right.fx_px) == (542.34, 536.07)  # the cameras exchanged
    np.testing.assert_allclose(p.T, [-0.0836, -0.001, 0.0], atol=1e-15)
    assert "left and right exchanged (--swap)" in p.provenance.notes
    assert main(["profile", "convert", str(src), "--to", "s2r", "-o", str(tmp_path / "kept.yaml"),
                 "--allow-bad-baseline"]) == 0
    assert "ERROR [baseline-side]" in capsys.readouterr().err


def test_convert_of_an_s2r_profile_says_s2r(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    dump_ros_pair(make_rig(), tmp_path / "ros")
    assert main(["profile", "convert", str(tmp_path / "ros"), "--to", "s2r", "-o", str(tmp_path / "a.yaml")]) == 0
    assert "read ROS camera_info:" in capsys.readouterr().out
    assert main(["profile", "convert", str(tmp_path / "a.yaml"), "--to", "s2r", "-o", str(tmp_path / "b.yaml")]) == 0
    assert capsys.readouterr().out.startswith("read s2r profile YAML:")


def test_camera_files_without_stereo_extrinsics(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = ("image_width: 640\nimage_height: 480\ncamera_name: cam\ncamera_matrix:\n  rows: 3\n  cols: 3\n"
            "  data: [500, 0, 320, 0, 500, 240, 0, 0, 1]\ndistortion_model: plumb_bob\n"
            "distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [0.1, -0.2, 0, 0, 0]\n")
    for side in ("left", "right"):
        (tmp_path / f"{side}.yaml").write_text(text)
    code = main(["profile", "convert", str(tmp_path / "left.yaml"), str(tmp_path / "right.yaml"), "--to", "s2r",
                 "-o", str(tmp_path / "p.yaml")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert "holds one camera's intrinsics but no stereo extrinsics (no rectification_matrix, no projection_matrix)" \
        in err and "required field is missing" not in err


def test_t_in_millimetres_names_units_m(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = _opencv(tmp_path / "mm.yml", "-64.0, 0.2, 0.1")
    assert main(["profile", "convert", str(src), "--to", "s2r", "-o", str(tmp_path / "p.yaml")]) == 2
    err = capsys.readouterr().err
    assert "T: |T| = 64.0004 m is beyond the 10 m any stereo baseline has" in err
    assert "pass --units-m 0.001 if T is in millimetres (0.064 m)" in err and err.count("\n") == 1
    assert main(["profile", "convert", str(src), "--to", "s2r", "-o", str(tmp_path / "p.yaml"), "--units-m",
                 "0.001"]) == 0
    assert load_any(tmp_path / "p.yaml").baseline_m == pytest.approx(0.0640004, abs=1e-7)


def test_lint_reads_a_camera_file_without_r_and_p(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The seed's published K (fx 381.36 at 640 px: 80 deg) with no R and P: lint compares it (exit 1, the FOV
    finding), instead of stopping at a missing rectification_matrix."""
    from tests.sources.rigs import SEED_URDF

    path = tmp_path / "left_camera_info.yaml"
    path.write_text("image_width: 640\nimage_height: 480\ncamera_name: left\ncamera_matrix:\n  rows: 3\n  cols: 3\n"
                    "  data: [381.36, 0, 320.5, 0, 381.36, 240.5, 0, 0, 1]\ndistortion_model: plumb_bob\n"
                    "distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [0, 0, 0, 0, 0]\n")
    assert main(["lint", str(SEED_URDF), "--camera-info", str(path)]) == 1
    assert "80.0 deg" in capsys.readouterr().out
