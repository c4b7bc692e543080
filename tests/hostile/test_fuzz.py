"""Fuzz suite (issue 14): every loader and the CLI on mutated and hostile inputs, seeded and bounded.

Properties: a loader returns a profile or raises one of s2r's own one-line errors; the CLI exits 0, 1 or 2
with at most one ``error:`` line and no traceback, writes nothing but its output, and never touches an existing
output without ``--force``; ``lint`` and ``profile from-urdf`` agree on what is refused; no xacro expression
outside the documented subset passes the check. (The s2r / ROS / Kalibr / RealSense text loaders are also
mutated by tests/formats/test_property.py; here they run through the CLI with the output checks.)
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from s2r.cli import main
from s2r.errors import S2RError
from s2r.formats.kalibr import kalibr_to_yaml
from s2r.formats.opencv import load_opencv, opencv_to_text
from s2r.formats.ros import camera_info_to_yaml, ros_pair_from_profile
from s2r.formats.s2r_yaml import profile_to_yaml
from s2r.profile import StereoProfile
from s2r.sources import lint_description, load_description_profile
from s2r.sources.urdf.xacro_sandbox import UnsafeXacro, check_expression
from tests.formats.rigs import distorted_rotated_rig
from tests.sources.rigs import XBOT_SDF, two_camera_urdf

FUZZ = settings(max_examples=15, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
RIG = distorted_rotated_rig()
_LEFT, _RIGHT = ros_pair_from_profile(RIG)
FORMATS_DATA = Path(__file__).resolve().parents[1] / "formats" / "data"
#: Valid inputs the mutations start from: name -> (file name, text).
BASES: dict[str, tuple[str, str]] = {
    "s2r": ("rig.yaml", profile_to_yaml(RIG)),
    "ros": ("left.yaml", camera_info_to_yaml(_LEFT)),
    "kalibr": ("camchain.yaml", kalibr_to_yaml(RIG, drop_k3=True)),
    "opencv-yaml": ("stereo.yml", opencv_to_text(RIG)),
    "opencv-xml": ("stereo.xml", opencv_to_text(RIG, xml=True)),
    "realsense": ("rs.txt", (FORMATS_DATA / "rs_enumerate_devices_d435.txt").read_text(encoding="utf-8")),
}
MJCF_RIG = """<mujoco><compiler angle="degree" eulerseq="xyz"/><visual><global offwidth="800" offheight="600"/></visual>
  <default><camera fovy="50"/><default class="rig"><camera resolution="640 480" sensorsize="0.0048 0.0036"
    focalpixel="610 605" principalpixel="2.5 -1.5" xyaxes="0 -1 0 0 0 1"/></default></default>
  <worldbody><body name="base" pos="0 0 0.4" euler="0 5 10"><joint type="hinge" axis="0 0 1"/><geom size="0.1"/>
    <frame pos="0.1 0 0.2" axisangle="0 1 0 -4"><body name="head" childclass="rig" pos="0 0 0.1" quat="1 0 0 0.02">
      <camera name="left" pos="0 0.045 0"/><camera name="right" pos="0 -0.045 0" mode="track"/>
  </body></frame></body></worldbody></mujoco>"""
DESCRIPTIONS: dict[str, tuple[str, str]] = {
    "urdf": ("rig.urdf", two_camera_urdf()),
    "sdf": ("rig.sdf", XBOT_SDF.read_text(encoding="utf-8")),
    "mjcf": ("scene.xml", MJCF_RIG),
}
ODD_NUMBERS = ["0", "-1", "1e308", "-1e308", "1e-300", "nan", "inf", "", "abc", "7", "100000", "2199023255552",
               "3.14159265", "1e6", '"5"', "0x10", "1_000"]
_NUMBER = re.compile(r"-?\d+\.?\d*(?:[eE][-+]?\d+)?")


@st.composite
def mutated(draw: st.DrawFn, text: str) -> bytes:
    """Replace numbers with odd values, truncate, flip a byte, drop or duplicate a line."""
    for _ in range(draw(st.integers(1, 3))):
        op = draw(st.sampled_from(["number", "number", "truncate", "flip", "drop_line", "dup_line"]))
        numbers = list(_NUMBER.finditer(text))
        lines = text.splitlines(keepends=True)
        if op == "number" and numbers:
            m = numbers[draw(st.integers(0, len(numbers) - 1))]
            text = text[:m.start()] + draw(st.sampled_from(ODD_NUMBERS)) + text[m.end():]
        elif op == "truncate":
            text = text[: draw(st.integers(0, len(text)))]
        elif op == "flip" and text:
            where = draw(st.integers(0, len(text) - 1))
            text = text[:where] + chr(draw(st.integers(32, 126))) + text[where + 1:]
        elif op in ("drop_line", "dup_line") and lines:
            i = draw(st.integers(0, len(lines) - 1))
            lines[i:i + 1] = [] if op == "drop_line" else [lines[i], lines[i]]
            text = "".join(lines)
    return text.encode("utf-8")


def _listing(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


def _cli(argv: list[str]) -> tuple[int, str]:
    err, out = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
        code = main(argv)
    return code, err.getvalue()


def _check_run(code: int, err: str) -> None:
    assert code in (0, 1, 2), err
    assert "Traceback" not in err and "internal error" not in err, err
    lines = err.strip().splitlines()
    assert sum(line.startswith("error: ") for line in lines) == (1 if code == 2 else 0), err
    assert all(line.startswith(("error: ", "warning: ")) for line in lines), err


@pytest.mark.parametrize("kind", sorted(BASES))
def test_convert_on_mutated_inputs(kind: str) -> None:
    name, text = BASES[kind]

    @FUZZ
    @given(content=mutated(text))
    def check(content: bytes) -> None:
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp)
            (folder / name).write_bytes(content)
            sources = [str(folder / name)]
            if kind == "ros":
                (folder / "right.yaml").write_text(camera_info_to_yaml(_RIGHT), encoding="utf-8")
                sources.append(str(folder / "right.yaml"))
            existing = folder / "existing.yaml"
            existing.write_text("keep me", encoding="utf-8")
            before = _listing(folder)
            code, err = _cli(["profile", "convert", *sources, "--to", "kalibr", "-o", str(existing)])
            _check_run(code, err)
            assert code == 2 and existing.read_text(encoding="utf-8") == "keep me"
            code, err = _cli(["profile", "convert", *sources, "--to", "s2r", "-o", str(folder / "out.yaml")])
            _check_run(code, err)
            assert _listing(folder) - before <= {"out.yaml"}  # nothing but the output
            assert (folder / "out.yaml").exists() == (code == 0)

    check()


@pytest.mark.parametrize("ext", ["yml", "xml"])
def test_opencv_loader_on_mutated_files(ext: str) -> None:
    _, text = BASES["opencv-yaml" if ext == "yml" else "opencv-xml"]

    @FUZZ
    @given(content=mutated(text))
    def check(content: bytes) -> None:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / f"stereo.{ext}"
            path.write_bytes(content)
            try:
                profile = load_opencv(path)
            except S2RError as exc:
                assert "\n" not in str(exc)
            else:
                assert isinstance(profile, StereoProfile)
                assert all(math.isfinite(v) for v in profile.T)

    check()


@pytest.mark.parametrize("kind", sorted(DESCRIPTIONS))
def test_lint_and_from_urdf_agree_on_mutated_descriptions(kind: str) -> None:
    """from-urdf refuses => lint refuses (exit 2) or reports an error; lint refuses => from-urdf refuses."""
    name, text = DESCRIPTIONS[kind]

    @FUZZ
    @given(content=mutated(text))
    def check(content: bytes) -> None:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / name
            path.write_bytes(content)
            try:
                findings = lint_description(path)
            except S2RError as exc:
                assert "\n" not in str(exc)
                with pytest.raises(S2RError):
                    load_description_profile(path, allow_bad_baseline=True)
                return
            try:
                load_description_profile(path, allow_bad_baseline=True)
            except S2RError:
                assert any(f.severity == "error" for f in findings), [f.code for f in findings]

    check()


_ATOMS = ["a", "x1", "pi", "radians(90)", "math.sqrt(2)", "cfg.fx", "cfg['w']", "1", "2.5", "'s'", "True",
          "__class__", "().__class__", "python.type", "xacro.message", "open", "_x", "x.__dict__", "'a'.format",
          "python", "math", "[c for c in ()]", "(lambda: 0)", "(y := 1)", "f(k=1)", "x.mro", "x.gi_frame",
          "xacro.arg('w')"]
_FORBIDDEN = ("__", "python.type", "xacro.message", "_x", "format", "lambda", " for ", ":=", "k=1", "mro",
              "gi_frame")


@st.composite
def expressions(draw: st.DrawFn) -> str:
    expr = draw(st.sampled_from(_ATOMS))
    for _ in range(draw(st.integers(0, 3))):
        op = draw(st.sampled_from(["+", "*", "**", " and ", " if c else ", "call", "attr", "index", "paren"]))
        other = draw(st.sampled_from(_ATOMS))
        if op == "call":
            expr = f"{draw(st.sampled_from(['sqrt', 'max', 'len', 'python.len', 'abs']))}({expr}, {other})"
        elif op == "attr":
            expr = f"({expr}).{draw(st.sampled_from(['real', 'fx', '__class__', 'upper', 'format']))}"
        elif op == "index":
            expr = f"{expr}[{other}]"
        elif op == "paren":
            expr = f"({expr})"
        else:
            expr = f"{expr}{op}{other}"
    return expr


@settings(max_examples=300, deadline=None, derandomize=True, database=None)
@given(expr=expressions())
def test_xacro_expression_check(expr: str) -> None:
    """Every expression holding a refused construct is refused; the check raises nothing but UnsafeXacro."""
    bad = any(token in expr for token in _FORBIDDEN) or re.search(r"(^|[^.\w])(python|math)($|[^.\w(])", expr)
    try:
        check_expression(expr)
    except UnsafeXacro:
        return
    assert not bad, f"{expr!r} passed the check"


HOSTILE_CLI: list[tuple[str, str, list[str]]] = [
    ("evil.urdf.xacro", '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="${[c for c in '
     "().__class__.__base__.__subclasses__()]}\"/></robot>", ["lint"]),
    ("evil.urdf.xacro", "<robot name=\"r\" xmlns:xacro=\"http://www.ros.org/wiki/xacro\"><link name=\"${xacro."
     "load_yaml('/etc/passwd')}\"/></robot>", ["profile", "from-urdf", "-o", "{out}"]),
    ("nocols.yml", BASES["opencv-yaml"][1].replace("   cols: 3\n", "", 1), ["profile", "convert", "--to", "s2r", "-o",
                                                                          "{out}"]),
    ("laughs.xml", '<?xml version="1.0"?><!DOCTYPE x [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;">]>'
     "<opencv_storage><name>&b;</name></opencv_storage>", ["profile", "convert", "--to", "s2r", "-o", "{out}"]),
    ("dup.yaml", BASES["s2r"][1] + "name: again\n", ["profile", "show"]),
]


@pytest.mark.parametrize(("name", "text", "argv"), HOSTILE_CLI, ids=[h[0] for h in HOSTILE_CLI])
def test_cli_subprocess_on_hostile_files(tmp_path: Path, name: str, text: str, argv: list[str]) -> None:
    """A real process per hostile file (a handful, not hundreds): exit 2, one line, no traceback, nothing
    written anywhere in its folder or working directory."""
    src = tmp_path / name
    src.write_text(text, encoding="utf-8")
    before = _listing(tmp_path)
    cmd = [sys.executable, "-m", "s2r", *argv[:2], str(src), *(a.replace("{out}", str(tmp_path / "out.yaml"))
                                                             for a in argv[2:])]
    env = {**os.environ, "HOME": str(tmp_path)}
    result = subprocess.run(cmd, capture_output=True, text=True, timeout=120, cwd=tmp_path, env=env)
    assert result.returncode == 2, result.stderr
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("error: "), result.stderr
    assert "root:" not in result.stderr + result.stdout
    assert _listing(tmp_path) == before
