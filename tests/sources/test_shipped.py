"""The shipped rigs and sim profiles: regenerating reproduces the shipped files byte for byte."""

from __future__ import annotations

from pathlib import Path

import pytest

from s2r.cli import main
from s2r.formats.s2r_yaml import profile_to_yaml
from s2r.registry import load_profile
from s2r.sources.shipped import SHIPPED, shipped_profiles
from tests.sources.rigs import REPO, SEED_URDF


def test_regenerating_reproduces_the_shipped_profiles() -> None:
    generated = shipped_profiles(REPO)
    assert sorted(generated) == sorted(REPO / p for p in SHIPPED)
    for path, profile in generated.items():
        assert path.read_text(encoding="utf-8") == profile_to_yaml(profile), f"regenerate {path}"


def test_regenerate_check_command(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["profile", "regenerate-sim", "--check"]) == 0
    assert capsys.readouterr().out == ""


def test_shipped_profiles_by_name() -> None:
    dual = load_profile("gazebo_dual_camera")
    assert dual.left.fx_px == pytest.approx(554.3827, abs=1e-4) and dual.T.tolist() == [-0.1, 0.0, 0.0]
    assert dual.provenance.sources[0].path == "urdf/dual_camera_fixed.urdf.xacro"
    xbot = load_profile("xbot_u_stereo")
    assert round(xbot.left.fx_px, 3) == 320.255 and (xbot.left.cx_px, xbot.left.cy_px) == (320.5, 240.5)
    assert xbot.T.tolist() == [-0.06, 0.0, 0.0] and xbot.provenance.convention == "gazebo-classic"
    assert xbot.simulation is not None and xbot.simulation.clip_near_m == 0.05


def test_seed_rig_matches_the_tutorial() -> None:
    text = SEED_URDF.read_text()
    for needle in ("xacro:macro", 'default="-0.1 0 0"', 'default="1.047"', 'default="640"', 'default="480"',
                   'default="0.1"', 'default="100"', 'default="30.0"', "<box size="):
        assert needle in text
    fixed = (REPO / "urdf" / "dual_camera_fixed.urdf.xacro").read_text()
    assert 'default="0 -0.1 0"' in fixed


def test_cli_from_urdf(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "xbot.yaml"
    assert main(["profile", "from-urdf", str(REPO / "urdf" / "xbot_u_stereo.sdf"), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "fx 320.255" in printed and "cx 320.50 cy 240.50" in printed and "T = (-0.0600, +0.0000, +0.0000)" in printed
    out2 = tmp_path / "seed.yaml"
    assert main(["profile", "from-urdf", str(SEED_URDF), "baseline_xyz:=0 -0.12 0", "--convention", "exact",
                 "--name", "seed_fixed", "-o", str(out2), "--json", "--arg", "width:=640"]) == 0
    assert '"output"' in capsys.readouterr().out
    p = load_profile(out2)
    assert p.name == "seed_fixed" and p.T.tolist() == pytest.approx([-0.12, 0, 0]) and p.left.cx_px == 319.5
