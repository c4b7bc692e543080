"""OpenCV's real stereo chessboard set (../shared/data): figures against plain OpenCV's reference."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.formats.s2r_yaml import load_profile_file
from tests.conftest import shared_data

#: The board of these sets (`calibrate` has no default board).
BOARD = ("--pattern", "9x6", "--square", "0.025")

pytestmark = pytest.mark.slow


def test_real_set_calibrates_like_opencv(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = shared_data("opencv_stereo_chessboard")
    out = tmp_path / "real.yaml"
    code = main(["calibrate", str(data), "--pattern", "9x6", "--square", "0.025", "-o", str(out), "--json",
                 "--jobs", "2"])
    figures = json.loads(capsys.readouterr().out)
    assert code == 0
    assert not [d for d in figures["dropped"] if not d["reason"].startswith("outlier")]  # every pair detected
    profile = load_profile_file(out)
    q = profile.provenance.calibration
    assert q is not None and q.rms_stereo_px is not None and q.rms_stereo_px <= 0.45
    assert abs(profile.left.fx_px - 536.07) <= 0.005 * 536.07
    assert abs(profile.baseline_m - 0.0836) <= 0.01 * 0.0836
    assert profile.left.std is not None and profile.left.std.fx_px is not None and profile.left.std.fx_px > 0
    assert profile.extrinsics.baseline_std_m is not None and profile.extrinsics.baseline_std_m > 0
    assert profile.provenance.origin == "real" and len(profile.provenance.sources) == 26
    assert q.epipolar_rms_px is not None and q.epipolar_rms_px < 0.5
    assert profile.T[0] < 0  # right camera to the right of the left one (OpenCV convention)
    # issue 11 bars: fx within 0.5 % of 536, baseline within 1 mm of 83.2 mm (default: k1k2p1p2, joint solve)
    assert abs(profile.left.fx_px - 536.0) <= 0.005 * 536.0 and abs(profile.baseline_m - 0.0832) <= 0.001
    assert figures["verdict"]["level"] in ("good", "check") and figures["model_comparison"]["best"]
    # rational: never a crash nor a NaN std (unobservable terms are named, their std unknown)
    code = main(["-q", "calibrate", *BOARD, str(data), "-o", str(tmp_path / "rational.yaml"),
                 "--distortion", "rational",
                 "--json", "--jobs", "2"])
    rational = json.loads(capsys.readouterr().out)
    assert code == 0 and "NaN" not in json.dumps(rational)


def _copy_set(src: Path, dst: Path, right_of: dict[str, str] | None = None, *, swap: bool = False,
              same: bool = False) -> Path:
    """left/ right/ copies of the real set: swapped sides, identical sides, or some right images moved."""
    import shutil

    for side in ("left", "right"):
        (dst / side).mkdir(parents=True)
    for f in sorted(src.glob("left*.jpg")):
        n = f.stem[4:]
        r = src / f"right{(right_of or {}).get(n, n)}.jpg"
        a, b = (r, f) if swap else (f, f if same else r)
        shutil.copy(a, dst / "left" / f"{n}.jpg")
        shutil.copy(b, dst / "right" / f"{n}.jpg")
    return dst


@pytest.mark.parametrize(("case", "message"), [
    ("swapped", "to the LEFT of the left camera"), ("identical", "identical"), ("millimetres", "--square")])
def test_classic_mistakes_exit_2_with_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str], case: str,
                                              message: str) -> None:
    data = shared_data("opencv_stereo_chessboard")
    folder = _copy_set(data, tmp_path / "set", swap=case == "swapped", same=case == "identical")
    square = "25" if case == "millimetres" else "0.025"
    code = main(["calibrate", str(folder), "--pattern", "9x6", "--square", square, "-o", str(tmp_path / "x.yaml"),
                 "--jobs", "2"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and message in err[-1] and "Traceback" not in "\n".join(err)
    if case == "swapped":
        assert main(["-q", "calibrate", *BOARD, str(folder), "-o", str(tmp_path / "s.yaml"),
                     "--swap", "--jobs", "2"]) == 0
        assert load_profile_file(tmp_path / "s.yaml").T[0] < 0
        capsys.readouterr()
        right_way = _copy_set(data, tmp_path / "ok")  # correct inputs with a wrong --swap: say to drop it
        assert main(["-q", "calibrate", *BOARD, str(right_way), "-o", str(tmp_path / "w.yaml"), "--swap",
                     "--jobs", "2"]) == 2
        line = capsys.readouterr().err.strip()
        assert "run without --swap" in line and "rerun with --swap" not in line


def test_shuffled_right_images_are_named_and_dropped(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = shared_data("opencv_stereo_chessboard")
    folder = _copy_set(data, tmp_path / "set", {"01": "07", "03": "01", "05": "03", "07": "05"})
    assert main(["calibrate", *BOARD, str(folder), "-o", str(tmp_path / "x.yaml"), "--json", "--jobs", "2"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert {d["name"] for d in figures["dropped"] if d["reason"].startswith("mismatched")} == {"01", "03", "05", "07"}
    assert abs(figures["baseline_m"] - 0.0832) < 0.002
