"""Bad MJCF input: ONE line naming the file and the element (exit 2 from ``profile from-description`` and ``lint``),
nothing written; includes confined to the scene's folder."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from s2r.cli import main

_CAMS = ('<camera name="left" pos="0 0.05 0" xyaxes="0 -1 0 0 0 1" {a}/>'
         '<camera name="right" pos="0 -0.05 0" xyaxes="0 -1 0 0 0 1" {a}/>')


def _scene(body: str = "", *, cams: str = 'resolution="640 480"', head: str = "") -> str:
    return f'<mujoco>{head}<worldbody><body name="head" pos="0 0 1">{_CAMS.format(a=cams)}{body}</body>' \
           '</worldbody></mujoco>'


def _refused(path: Path, capsys: pytest.CaptureFixture[str], *needles: str, extra: tuple[str, ...] = ()) -> str:
    out = path.with_suffix(".yaml")
    for argv in (["profile", "from-description", str(path), *extra, "-o", str(out)], ["lint", str(path), *extra]):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip()
        assert err.startswith("error: ") and "\n" not in err, err
        assert str(path) in err, err
        for needle in needles:
            assert needle in err, err
    assert not out.exists()
    return err


CASES = {
    "malformed": ("<mujoco><worldbody></mujoco>", ("malformed XML", "line 1")),
    "doctype": ('<!DOCTYPE m [<!ENTITY a "b">]><mujoco/>', ("DOCTYPE",)),
    "fovy_180": (_scene(cams='fovy="180" resolution="640 480"'), ("<camera name='left'> line 1: fovy", "180")),
    "fovy_text": (_scene(cams='fovy="wide" resolution="640 480"'), ("fovy", "expected 1 number")),
    "resolution_zero": (_scene(cams='resolution="0 480"'), ("resolution", "whole pixels")),
    "resolution_huge": (_scene(cams='resolution="100000 480"'), ("resolution", "whole pixels")),
    "resolution_fraction": (_scene(cams='resolution="640.5 480"'), ("resolution", "whole pixels")),
    "sensor_negative": (_scene(cams='resolution="640 480" sensorsize="-0.006 0.004" focal="0.004 0.004"'),
                        ("sensorsize", "negative")),
    "focal_in_mm": (_scene(cams='resolution="640 480" sensorsize="0.006 0.004" focal="4 4"'), ("focal", "beyond 1 m")),
    "focal_without_sensor": (_scene(cams='resolution="640 480" focalpixel="500 500"'), ("need sensorsize",)),
    "pixels_without_resolution": (_scene(cams='sensorsize="0.006 0.004" focalpixel="500 500"'),
                                  ("resolution", "focalpixel/principalpixel need a resolution")),
    "no_focal": (_scene(cams='resolution="640 480" sensorsize="0.006 0.004" principal="0.0001 0"'),
                 ("positive focal length",)),
    "orthographic": (_scene(cams='resolution="640 480" projection="orthographic"'), ("not a pinhole",)),
    "two_orientations": (_scene(cams='resolution="640 480" quat="1 0 0 0"'), ("multiple orientation attributes",)),
    "zero_quat": (_scene(body='<camera name="c" quat="0 0 0 0"/>'), ("<camera name='c'> line 1: quat", "zero")),
    "zero_axis": (_scene(body='<body name="b" axisangle="0 0 0 30"/>'), ("<body name='b'> line 1: axisangle",)),
    "unknown_class": (_scene(cams='resolution="640 480" class="nope"'), ("unknown default class 'nope'",)),
    "unknown_childclass": ('<mujoco><worldbody><body childclass="x"/></worldbody></mujoco>',
                           ("unknown default class 'x'", "childclass")),
    "huge_pos": (_scene(body='<body name="far" pos="1e9 0 0"/>'), ("<body name='far'> line 1: pos", "beyond")),
    "targetbodycom": (_scene(cams='resolution="640 480" mode="targetbodycom" target="head"'),
                      ("targetbodycom", "centre of mass")),
    "targetbody_no_target": (_scene(cams='resolution="640 480" mode="targetbody"'), ("target",)),
    "unknown_mode": (_scene(cams='resolution="640 480" mode="orbit"'), ("unknown camera mode 'orbit'",)),
    "compiler_angle": (_scene(head='<compiler angle="grad"/>'), ("<compiler> line 1: angle",)),
    "eulerseq": (_scene(head='<compiler eulerseq="xyw"/>'), ("eulerseq",)),
    "replicate_camera": (_scene(body='<replicate count="2" offset="0 0.1 0"><camera name="r"/></replicate>'),
                         ("<replicate", "cameras inside <replicate> are not read")),
    "duplicate_class": ('<mujoco><default><default class="a"/><default class="a"/></default></mujoco>',
                        ("defined twice",)),
    "no_cameras": ("<mujoco><worldbody/></mujoco>", ("no <camera> found in the MJCF",)),
}


@pytest.mark.parametrize("case", list(CASES))
def test_bad_scene_is_one_line(case: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text, needles = CASES[case]
    path = tmp_path / "scene.xml"
    path.write_text(text, encoding="utf-8")
    _refused(path, capsys, *needles)


def test_unknown_camera_lists_the_names(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "scene.xml"
    path.write_text(_scene(body='<camera name="top" pos="0 0 2"/>'), encoding="utf-8")
    _refused(path, capsys, "--left", "no camera named 'eye'", "cameras: left, right, top",
             extra=("--left", "eye", "--right", "right"))


def test_gazebo_convention_is_refused_for_mjcf(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "scene.xml"
    path.write_text(_scene(), encoding="utf-8")
    assert main(["profile", "from-description", str(path), "--convention", "gazebo-classic", "-o",
                 str(tmp_path / "p.yaml")]) == 2
    err = capsys.readouterr().err
    assert "--convention" in err and "exact" in err and not (tmp_path / "p.yaml").exists()


def test_existing_output_is_kept(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "scene.xml"
    path.write_text(_scene(), encoding="utf-8")
    out = tmp_path / "p.yaml"
    out.write_text("mine", encoding="utf-8")
    assert main(["profile", "from-description", str(path), "-o", str(out)]) == 2
    assert out.read_text(encoding="utf-8") == "mine" and "--force" in capsys.readouterr().err


def _include_scene(tmp_path: Path, name: str) -> Path:
    scene = tmp_path / "scene" / "scene.xml"
    scene.parent.mkdir(exist_ok=True)
    scene.write_text(_scene(body=f'<include file="{name}"/>'), encoding="utf-8")
    return scene


@pytest.mark.parametrize("name", ["../outside.xml", "parts/../../outside.xml", "/etc/hostname"])
def test_include_outside_the_folder(name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "outside.xml").write_text('<mujoco><camera name="x"/></mujoco>', encoding="utf-8")
    _refused(_include_scene(tmp_path, name), capsys, "<include> line 1: file",
             "points outside the description's folder")


def test_include_symlink_leaving_the_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "outside.xml").write_text('<mujoco><camera name="x"/></mujoco>', encoding="utf-8")
    scene = _include_scene(tmp_path, "link.xml")
    os.symlink(tmp_path / "outside.xml", scene.parent / "link.xml")
    _refused(scene, capsys, "'link.xml' points outside the description's folder")


def test_include_missing_twice_and_too_deep(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scene = _include_scene(tmp_path, "missing.xml")
    _refused(scene, capsys, "'missing.xml' not found")
    folder = scene.parent
    (folder / "part.xml").write_text("<mujoco><site/></mujoco>", encoding="utf-8")
    scene.write_text(_scene(body='<include file="part.xml"/><include file="part.xml"/>'), encoding="utf-8")
    _refused(scene, capsys, "already included")
    for level in range(12):
        (folder / f"d{level}.xml").write_text(f'<mujoco><include file="d{level + 1}.xml"/></mujoco>',
                                              encoding="utf-8")
    scene.write_text(_scene(body='<include file="d0.xml"/>'), encoding="utf-8")
    _refused(scene, capsys, "<include> line 1 of d7.xml", "nested more than 8 deep")
    (folder / "self.xml").write_text('<mujoco><include file="self.xml"/></mujoco>', encoding="utf-8")
    scene.write_text(_scene(body='<include file="self.xml"/>'), encoding="utf-8")
    _refused(scene, capsys, "already included")


def test_include_budget(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scene = _include_scene(tmp_path, "x.xml")
    for index in range(260):
        (scene.parent / f"p{index}.xml").write_text("<mujoco><site/></mujoco>", encoding="utf-8")
    scene.write_text(_scene(body="".join(f'<include file="p{i}.xml"/>' for i in range(260))), encoding="utf-8")
    _refused(scene, capsys, "more than 256 included files")
