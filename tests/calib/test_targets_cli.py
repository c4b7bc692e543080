"""`s2r calibrate --target / --lens`: bad input is one line and exit 2; fisheye profiles travel through formats."""

from __future__ import annotations

from pathlib import Path

import pytest

from s2r.cli import main
from s2r.formats import kalibr, opencv, ros, ros_read
from s2r.profile import Distortion
from tests.conftest import make_rig


@pytest.mark.parametrize(("args", "field"), [
    (["--target", "{bad}"], "tagSize"),
    (["--target", "{missing}"], "file not found"),
    (["--lens", "fisheye", "--distortion", "rational"], "--distortion"),
])
def test_bad_target_or_lens_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str],
                                        field: str) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("target_type: aprilgrid\ntagCols: 6\ntagRows: 6\ntagSize: 0\ntagSpacing: 0.3\n")
    args = [a.format(bad=bad, missing=tmp_path / "none.yaml") for a in args]
    out = tmp_path / "rig.yaml"
    code = main(["calibrate", str(tmp_path), "-o", str(out), "--pattern", "9x6", "--square", "0.025", *args])
    err = capsys.readouterr().err.strip()
    assert code == 2 and field in err and len(err.splitlines()) == 1 and "Traceback" not in err
    assert not out.exists()


def test_fisheye_profile_round_trips_through_formats(tmp_path: Path) -> None:
    rig = make_rig(name="fish")
    d = Distortion(model="equidistant", coefficients=(-0.007, 0.043, -0.041, 0.0076))
    rig = rig.model_copy(update={"left": rig.left.model_copy(update={"distortion": d}),
                                 "right": rig.right.model_copy(update={"distortion": d})})
    kalibr.dump_kalibr(rig, tmp_path / "camchain.yaml")
    opencv.dump_opencv(rig, tmp_path / "stereo.yaml")
    ros.dump_ros_pair(rig, tmp_path / "ros")
    for back in (kalibr.load_kalibr(tmp_path / "camchain.yaml"), opencv.load_opencv(tmp_path / "stereo.yaml"),
                 ros_read.load_ros_pair(tmp_path / "ros" / "left.yaml", tmp_path / "ros" / "right.yaml")):
        assert back.left.distortion.model == "equidistant"
        assert back.left.distortion.coefficients == pytest.approx(d.coefficients, abs=1e-6)
    assert "equidistant" in (tmp_path / "camchain.yaml").read_text()
