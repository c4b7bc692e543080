"""Issue 14 items 7 and 9: crashes become exit 2 with one line, and absurd values are refused by the model's
physical bounds (the reason in the message); lint and from-urdf agree on the same description."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from s2r.cli import main
from s2r.errors import ProfileError
from s2r.formats.s2r_yaml import load_profile_file
from s2r.profile import Camera, StereoProfile
from tests.sources.rigs import FIXED_URDF, sensor, two_camera_urdf, write

#: The board of these sets (`calibrate` has no default board).
BOARD = ("--pattern", "9x6", "--square", "0.025")

REPO = Path(__file__).resolve().parents[2]
PROFILE = REPO / "profiles" / "real" / "realsense_d435_848x480.yaml"


def _one_error(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith("error: ") and "Traceback" not in err
    return err


@pytest.mark.parametrize(("arg", "fragment"), [
    ("width:=1e308", "image width must be a whole number of pixels from 16 to 16384"),
    ("height:=7", "image height must be a whole number"),
    ("width:=100000", "from 16 to 16384"),
    ("clip_near:=200", "<clip><far> 100 m must exceed <near> 200 m"),
    ("clip_near:=-1", "<clip><near> (metres) must be positive"),
    ("update_rate:=-30", "<update_rate>"),
    ("hfov:=0", "horizontal_fov 0.0 rad is outside"),
    ("hfov:=", "<horizontal_fov> is empty"),
    ("baseline_xyz:=1e308 0 0", "beyond 1e+06"),
])
def test_lint_and_from_urdf_agree_on_bad_values(tmp_path: Path, capsys: pytest.CaptureFixture[str], arg: str,
                                                fragment: str) -> None:
    lint = _one_error(["lint", str(FIXED_URDF), arg], capsys)
    made = _one_error(["profile", "from-urdf", str(FIXED_URDF), arg, "-o", str(tmp_path / "p.yaml")], capsys)
    assert fragment in lint and fragment in made
    assert not (tmp_path / "p.yaml").exists()


@pytest.mark.parametrize(("xyz", "rpy", "fragment"), [("0 -0.1 0", "0 0 3.14159265", "turned 180.0 deg from the left"),
                                                 ("0 -20 0", "0 0 0", "exceeds 10 m")])
def test_pair_beyond_the_bounds_is_refused_by_from_urdf_and_an_error_for_lint(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], xyz: str, rpy: str, fragment: str) -> None:
    path = write(tmp_path, "turned.urdf", two_camera_urdf(right_xyz=xyz, right_rpy=rpy))
    err = _one_error(["profile", "from-urdf", str(path), "-o", str(tmp_path / "p.yaml")], capsys)
    assert fragment in err
    assert main(["lint", str(path)]) == 1  # an error-level finding
    out = capsys.readouterr().out
    assert "[invalid-profile]" in out and fragment in out


@pytest.mark.parametrize(("lens", "fragment"), [
    ("<fx>0</fx><fy>500</fy><cx>320</cx><cy>240</cy>", "<fx> (focal length in pixels) must be positive"),
    ("<fx>-5</fx><fy>500</fy><cx>320</cx><cy>240</cy>", "must be positive"),
    ("<fx>1e308</fx><fy>500</fy><cx>320</cx><cy>240</cy>", "narrower than any real lens"),
])
def test_gz_sim_lens_intrinsics(tmp_path: Path, capsys: pytest.CaptureFixture[str], lens: str,
                                fragment: str) -> None:
    extra = f"<lens><intrinsics>{lens}</intrinsics></lens>"
    text = two_camera_urdf(left_sensor=sensor("left_cam", extra=extra), right_sensor=sensor("right_cam", extra=extra))
    path = write(tmp_path, "lens.urdf", text)
    err = _one_error(["profile", "from-urdf", str(path), "--convention", "gz-sim", "-o", str(tmp_path / "p.yaml")],
                     capsys)
    assert fragment in err


def _profile_data() -> dict[str, Any]:
    data: dict[str, Any] = yaml.safe_load(PROFILE.read_text(encoding="utf-8"))
    return data


def _set(data: dict[str, Any], dotted: str, value: Any) -> None:
    *parents, last = dotted.split(".")
    for key in parents:
        data = data[key]
    data[last] = value


@pytest.mark.parametrize(("field", "value", "fragment"), [
    ("extrinsics.translation_m", [1e308, 0.0, 0.0], "exceeds 10 m"),
    ("extrinsics.translation_m", [-1e6, 0.0, 0.0], "exceeds 10 m"),
    ("extrinsics.translation_m", [-0.0001, 0.0, 0.0], "baseline 0.0001 m is outside"),
    ("extrinsics.rotation", [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]], "turned 180.0 deg"),
    ("left.width_px", 100000, "less than or equal to 16384"),
    ("left.width_px", 2**40, "less than or equal to 16384"),
    ("left.fx_px", 1e308, "narrower than any real lens"),
    ("left.fx_px", 1e-300, "wider than a pinhole camera can image"),
    ("left.fx_px", "640", "expected a number, got '640'"),
    ("left.skew", 1e9, "skew 1e+09 exceeds fx"),
    ("left.distortion.coefficients", [1e6, 0.0, 0.0, 0.0, 0.0], "exceeds 100000 in magnitude"),
    ("left.distortion.coefficients", [0.1, "0", 0.0, 0.0, 0.0], "expected a number, got '0'"),
    ("provenance.convention", "bogus", "'gazebo-classic', 'gz-sim', 'exact' or 'opencv'"),
    ("simulation", {"clip_near_m": 5.0, "clip_far_m": 1.0}, "must exceed clip_near_m"),
    ("simulation", {"update_rate_hz": -30}, "greater than 0"),
    ("matcher.min_depth_m", True, "expected a number, got True"),
])
def test_absurd_profile_values_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str], field: str,
                                           value: Any, fragment: str) -> None:
    data = _profile_data()
    _set(data, field, value)
    path = tmp_path / "p.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    with pytest.raises(ProfileError, match=None) as info:
        load_profile_file(path)
    assert fragment in str(info.value)
    assert fragment in _one_error(["profile", "show", str(path)], capsys)


def test_fisheye_beyond_180_degrees_is_still_a_profile() -> None:
    """The equidistant model keeps working past 180 deg (a 200 deg fisheye: f = W / (2 * 100 deg in rad))."""
    width = 1280
    fx = width / 2 / (100 * 3.141592653589793 / 180)
    cam = Camera(width_px=width, height_px=width, fx_px=fx, fy_px=fx, cx_px=639.5, cy_px=639.5,
                 distortion={"model": "equidistant", "coefficients": (0.01, 0.0, 0.0, 0.0)})  # type: ignore[arg-type]
    assert cam.fx_px == pytest.approx(366.7, abs=0.1)
    with pytest.raises(ValueError, match="wider than a pinhole"):  # 2 atan(640 / 30) = 174.6 deg
        Camera(width_px=width, height_px=width, fx_px=30.0, fy_px=30.0, cx_px=639.5, cy_px=639.5)
    with pytest.raises(ValueError, match="wider than an equidistant"):  # 2 * 640 / 200 rad = 367 deg
        Camera(width_px=width, height_px=width, fx_px=200.0, fy_px=200.0, cx_px=639.5, cy_px=639.5,
               distortion={"model": "equidistant", "coefficients": (0.0, 0.0, 0.0, 0.0)})  # type: ignore[arg-type]


def test_shipped_profiles_are_within_bounds() -> None:
    for path in sorted((REPO / "profiles").rglob("*.yaml")):
        assert isinstance(load_profile_file(path), StereoProfile)


@pytest.mark.parametrize(("edit", "fragment"), [
    (("camera_matrix", 8, 5.0), "last row must be [0 0 1]"),
    (("projection_matrix", 3, 1e300), "beyond 1e+09"),
])
def test_ros_camera_info_values(tmp_path: Path, capsys: pytest.CaptureFixture[str], edit: tuple[str, int, float],
                                fragment: str) -> None:
    assert main(["profile", "convert", str(PROFILE), "--to", "ros", "-o", str(tmp_path / "ros")]) == 0
    key, index, value = edit
    right = tmp_path / "ros" / "right.yaml"
    data = yaml.safe_load(right.read_text(encoding="utf-8"))
    data[key]["data"][index] = value
    right.write_text(yaml.safe_dump(data), encoding="utf-8")
    capsys.readouterr()
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no raw numpy RuntimeWarning on the way
        err = _one_error(["profile", "convert", str(tmp_path / "ros"), "--to", "s2r", "-o", str(tmp_path / "p.yaml")],
                         capsys)
    assert fragment in err


@pytest.mark.parametrize("alpha", ["nan", "5", "-3", "inf"])
def test_depth_alpha_out_of_range(tmp_path: Path, capsys: pytest.CaptureFixture[str], alpha: str) -> None:
    code = main(["depth", "a.png", "b.png", "--profile", str(PROFILE), "--alpha", alpha, "-o", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and "--alpha" in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("fx", [1e308, 1e-300])
def test_validate_refuses_absurd_focal_lengths(tmp_path: Path, capsys: pytest.CaptureFixture[str], fx: float) -> None:
    data = _profile_data()
    _set(data, "left.fx_px", fx)
    path = tmp_path / "p.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    err = _one_error(["validate", str(path), "--quick", "-o", str(tmp_path / "report")], capsys)
    assert "field of view" in err and not (tmp_path / "report").exists()


@pytest.mark.parametrize("kind", ["existing", "fifo", "symlink"])
def test_calibrate_checks_output_before_any_work(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                 kind: str) -> None:
    import os

    out = tmp_path / "out.yaml"
    if kind == "existing":
        out.write_text("keep", encoding="utf-8")
    elif kind == "fifo":
        os.mkfifo(out)
    else:
        out.symlink_to(tmp_path / "target.yaml")
    (tmp_path / "images").mkdir()  # an empty input: the output is refused before the input is even read
    err = _one_error(["calibrate", *BOARD, str(tmp_path / "images"), "-o", str(out)], capsys)
    assert str(out) in err and "image" not in err.split(str(out), 1)[1].split("(")[0]
    assert not (tmp_path / "out.yaml.corners").exists()
