"""Issue 24 item 5: a legacy macro call without the ``xacro:`` prefix (ROS 1 before --inorder) is named, with the
prefix that fixes it, also when the macro is defined in an included file (``<BB2-08S2C-38 .../>`` in Clearpath's
accessories, ``<sensor_d435 .../>`` with realsense2_description's ``_d435.urdf.xacro``)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from s2r.cli import main

CLEARPATH = Path(__file__).parent / "fixtures" / "clearpath"
D435_MACRO = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:macro name="sensor_d435" params="parent *origin name:=camera">
    <joint name="${name}_joint" type="fixed"><xacro:insert_block name="origin"/>
      <parent link="${parent}"/><child link="${name}_link"/></joint>
    <link name="${name}_link"/>
  </xacro:macro>
</robot>
"""
D435_TOP = """<?xml version="1.0"?>
<robot name="realsense2_camera" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:include filename="$(find realsense2_description)/urdf/_d435.urdf.xacro"/>
  <link name="base_link"/>
  <sensor_d435 parent="base_link">
    <origin xyz="0 0 0" rpy="0 0 0"/>
  </sensor_d435>
</robot>
"""


def _one_error_line(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: ")
    return err


def test_legacy_bb2_call_in_an_included_file_is_named(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tree = tmp_path / "clearpath"
    shutil.copytree(CLEARPATH, tree)
    accessories = tree / "jackal_description" / "urdf" / "accessories.urdf.xacro"
    text = accessories.read_text().replace("<xacro:BB2-08S2C-38 frame", "<BB2-08S2C-38 frame")
    accessories.write_text(text)
    line = next(n for n, t in enumerate(text.splitlines(), start=1) if "<BB2-08S2C-38 frame" in t)
    top = tree / "jackal_description" / "urdf" / "jackal.urdf.xacro"
    for command in (["lint"], ["profile", "from-urdf"]):
        extra = ["-o", str(tmp_path / "p.yaml")] if command[0] == "profile" else []
        err = _one_error_line([*command, str(top), "--package-path", str(tree), "--env", "JACKAL_BB2=1", *extra],
                              capsys)
        assert f"{accessories.resolve()}: <BB2-08S2C-38> line {line}: <BB2-08S2C-38> is a legacy macro call" in err
        assert "write <xacro:BB2-08S2C-38 .../>" in err and "is not declared" not in err


def test_legacy_sensor_d435_call_is_named(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    package = tmp_path / "realsense2_description"
    (package / "urdf").mkdir(parents=True)
    (package / "package.xml").write_text("<package><name>realsense2_description</name></package>")
    (package / "urdf" / "_d435.urdf.xacro").write_text(D435_MACRO)
    top = tmp_path / "robot" / "test_d435.urdf.xacro"
    top.parent.mkdir()
    top.write_text(D435_TOP)
    err = _one_error_line(["profile", "from-urdf", str(top), "--package-path", str(tmp_path), "-o",
                           str(tmp_path / "p.yaml")], capsys)
    assert f"{top}: <sensor_d435> line 5: <sensor_d435> is a legacy macro call" in err
    assert "write <xacro:sensor_d435 .../>" in err and "no camera sensor found" not in err
    top.write_text(D435_TOP.replace("<sensor_d435", "<xacro:sensor_d435").replace("</sensor_d435",
                                                                                   "</xacro:sensor_d435"))
    err = _one_error_line(["profile", "from-urdf", str(top), "--package-path", str(tmp_path), "-o",
                           str(tmp_path / "p.yaml")], capsys)
    assert "no camera sensor found" in err  # the macro (links only) expands; it defines no camera
