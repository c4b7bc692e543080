"""Descriptions as people name and split them: ``robot.gazebo`` xacro, legacy macro calls, SDF model:// includes."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.errors import SourceError
from s2r.sources import load_description_profile

FIXTURES = Path(__file__).parent / "fixtures"
BB2 = FIXTURES / "pointgrey_bumblebee2.urdf.xacro"


def test_xacro_by_content_whatever_the_suffix(tmp_path: Path) -> None:
    gazebo = tmp_path / "jackal.gazebo"
    gazebo.write_text(BB2.read_text())
    assert load_description_profile(gazebo).baseline_m == pytest.approx(0.12, abs=1e-9)


def test_legacy_macro_call_is_named(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    legacy = tmp_path / "legacy.urdf.xacro"
    legacy.write_text(BB2.read_text().replace("<xacro:pointgrey_bumblebee2 frame", "<pointgrey_bumblebee2 frame"))
    with pytest.raises(SourceError, match="legacy macro call without the xacro: prefix"):
        load_description_profile(legacy)
    assert main(["profile", "from-urdf", str(legacy), "-o", str(tmp_path / "p.yaml")]) == 2
    err = capsys.readouterr().err.strip()
    line = int(err.split("<pointgrey_bumblebee2> line ")[1].split(":")[0])
    assert "<pointgrey_bumblebee2 frame" in legacy.read_text().splitlines()[line - 1] and len(err.splitlines()) == 1


def test_model_uri_include_resolved_through_the_resource_path(monkeypatch: pytest.MonkeyPatch,
                                                              capsys: pytest.CaptureFixture[str],
                                                              tmp_path: Path) -> None:
    """Two sensors at y = +-0.035 in the included model: T = (-0.07, 0, 0); fx = 640 / tan(0.6) = 936.2 px."""
    world = FIXTURES / "gz_world_with_include.sdf"
    monkeypatch.delenv("GZ_SIM_RESOURCE_PATH", raising=False)
    monkeypatch.delenv("GAZEBO_MODEL_PATH", raising=False)
    monkeypatch.delenv("IGN_GAZEBO_RESOURCE_PATH", raising=False)
    assert main(["profile", "from-urdf", str(world), "-o", str(tmp_path / "a.yaml")]) == 2
    err = capsys.readouterr().err
    assert "model 'stereo_camera' (model://stereo_camera) not found" in err and "GZ_SIM_RESOURCE_PATH" in err
    monkeypatch.setenv("GZ_SIM_RESOURCE_PATH", str(FIXTURES / "models"))
    p = load_description_profile(world, convention="gz-sim")
    assert pytest.approx([-0.07, 0.0, 0.0], abs=1e-12) == p.T
    assert p.left.fx_px == pytest.approx(640 / math.tan(0.6), abs=1e-9) and p.left.cx_px == 640.0
    monkeypatch.delenv("GZ_SIM_RESOURCE_PATH")
    p2 = load_description_profile(world, package_paths=[FIXTURES / "models"])
    assert pytest.approx([-0.07, 0.0, 0.0], abs=1e-12) == p2.T
