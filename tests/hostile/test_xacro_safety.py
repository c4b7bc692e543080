"""Issue 14 items 1-2: a ``.xacro`` from a stranger runs no code, reads no file outside its package and copies
no environment value into outputs (reproducers of the fuzzing findings, through the CLI in-process)."""

from __future__ import annotations

from pathlib import Path

import pytest

from s2r.cli import main
from s2r.errors import SourceError
from s2r.sources.urdf.xacro import expand_xacro
from s2r.sources.urdf.xacro_sandbox import UnsafeXacro, check_expression
from tests.sources.rigs import FIXED_URDF

CANARY = "S2R_CANARY_7f3a9c"


def _rig(tmp_path: Path, *, prop: str = "", sensor_name: str = "${side}_camera", robot: str = "rig") -> Path:
    """The fixed dual-camera xacro with an extra property line and a replaced sensor name / robot name."""
    text = FIXED_URDF.read_text(encoding="utf-8")
    text = text.replace('name="${side}_camera"', f'name="{sensor_name}"')
    text = text.replace('<robot name="dual_camera_fixed"', f'<robot name="{robot}"')
    text = text.replace("<xacro:arg name=\"baseline_xyz\"", f"{prop}\n  <xacro:arg name=\"baseline_xyz\"", 1)
    path = tmp_path / "desc" / "rig.urdf.xacro"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out + err


def _both(path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> list[tuple[int, str]]:
    out = tmp_path / "out.yaml"
    results = [_run(["lint", str(path)], capsys),
               _run(["profile", "from-urdf", str(path), "-o", str(out)], capsys)]
    if out.exists():
        results.append((0, out.read_text(encoding="utf-8")))
    return results


@pytest.mark.parametrize("expr", [
    # the finding: xacro's filter checks only the outer code's names; the comprehension's body escapes it
    "[d for c in [()] for d in c.__class__.__base__.__subclasses__() if d.__name__ == 'Popen'][0]"
    "(['touch', '{marker}'])",
    "[d for d in [0]][0].__class__",
    "(lambda: 1)()",
    "python.type(1)",
    "python.vars(xacro)",
    "'x'.format(1)",
    "'{marker}'.upper()",
    "xacro.message('x')",
])
def test_malicious_expressions_are_refused_before_evaluation(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                             expr: str) -> None:
    marker = tmp_path / "MARKER"
    path = _rig(tmp_path, prop=f'<xacro:property name="evil" value="${{{expr.format(marker=marker)}}}"/>',
                sensor_name="${evil}_${side}")
    for code, text in _both(path, tmp_path, capsys):
        assert code == 2, text
        assert "refused" in text and "Traceback" not in text
        assert text.count("error:") == 1  # reported once, not twice
    assert not marker.exists()


def test_marker_exploit_ran_under_plain_xacro(tmp_path: Path) -> None:
    """Anchor: the same expression does run code under plain xacro (so the refusal above is not vacuous)."""
    import xacro

    marker = tmp_path / "MARKER"
    expr = (f"[d for c in [()] for d in c.__class__.__base__.__subclasses__() if d.__name__ == 'Popen'][0]"
            f"(['touch', '{marker}']).wait()")
    path = _rig(tmp_path, prop=f'<xacro:property name="evil" value="${{{expr}}}"/>', sensor_name="${evil}_${side}")
    xacro.process_file(str(path), mappings={})
    assert marker.exists()


@pytest.mark.parametrize("name", ["/etc/passwd", "../secret.yaml"])
def test_load_yaml_outside_the_description_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                      name: str) -> None:
    (tmp_path / "secret.yaml").write_text(f"token: {CANARY}\n", encoding="utf-8")
    path = _rig(tmp_path, prop=f"<xacro:property name=\"cfg\" value=\"${{xacro.load_yaml('{name}')}}\"/>",
                sensor_name="${cfg}_${side}")
    for code, text in _both(path, tmp_path, capsys):
        assert code == 2 and "outside the description's folder" in text
        assert CANARY not in text and "root:" not in text


def test_load_yaml_inside_the_description_and_package_path_works(tmp_path: Path) -> None:
    pkg = tmp_path / "pkgs" / "cams"
    pkg.mkdir(parents=True)
    (pkg / "cam.yaml").write_text("width: 320\n", encoding="utf-8")
    path = _rig(tmp_path, prop="<xacro:property name=\"cfg\" value=\"${xacro.load_yaml('cfg.yaml')}\"/>\n"
                "  <xacro:property name=\"ext\" value=\"${load_yaml('$(find cams)/cam.yaml')}\"/>",
                sensor_name="s${cfg.scale * ext['width'] + math.floor(radians(180) / pi)}_${side}")
    (path.parent / "cfg.yaml").write_text("scale: 2\n", encoding="utf-8")
    text = expand_xacro(path, package_paths=[tmp_path / "pkgs"])
    assert 'name="s641_left"' in text


def test_environment_is_never_read(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                   monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("S2R_SECRET", CANARY)
    path = _rig(tmp_path, robot="$(optenv S2R_SECRET fallback)", sensor_name="$(optenv S2R_SECRET cam)_${side}")
    out = tmp_path / "p.yaml"
    code, text = _run(["profile", "from-urdf", str(path), "-o", str(out), "--json"], capsys)
    assert code == 0, text
    assert CANARY not in text and CANARY not in out.read_text(encoding="utf-8")
    code, text = _run(["lint", str(path), "--json"], capsys)
    assert CANARY not in text
    env_path = _rig(tmp_path, sensor_name="$(env S2R_SECRET)_${side}")
    for code, text in _both(env_path, tmp_path / "x", capsys):
        assert code == 2 and "does not read the environment" in text and CANARY not in text


def test_eval_substitution_cannot_reach_builtins(tmp_path: Path) -> None:
    path = _rig(tmp_path, robot="$(eval open)")
    with pytest.raises(SourceError, match="builtin 'open' is refused"):
        expand_xacro(path)


def test_include_outside_the_package_is_refused(tmp_path: Path) -> None:
    outside = f'<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="{CANARY}"/></robot>'
    (tmp_path / "outside.xacro").write_text(outside, encoding="utf-8")
    path = _rig(tmp_path, prop='<xacro:include filename="../outside.xacro"/>')
    with pytest.raises(SourceError, match="include of") as info:
        expand_xacro(path)
    assert CANARY not in str(info.value)


def test_yaml_error_in_loaded_file_is_not_quoted(tmp_path: Path) -> None:
    path = _rig(tmp_path, prop="<xacro:property name=\"cfg\" value=\"${xacro.load_yaml('bad.yaml')}\"/>",
                sensor_name="${cfg}_${side}")
    (path.parent / "bad.yaml").write_text(f"key: [{CANARY}\nother: : :\n", encoding="utf-8")
    with pytest.raises(SourceError) as info:
        expand_xacro(path)
    assert CANARY not in str(info.value) and "malformed YAML" in str(info.value)


@pytest.mark.parametrize("expr", ["1 + 2 * 3", "radians(90) / 2", "math.atan2(1, 2)", "a if b > 0 else -c",
                                  "cfg['x'][0] ** 2", "cfg.left.fx", "[1, 2.5, 'a']", "xacro.arg('w')",
                                  "not (a and b) or c", "python.len([1, 2])", "'%s_%d' % (side, 2)"])
def test_ordinary_expressions_are_allowed(expr: str) -> None:
    check_expression(expr)


@pytest.mark.parametrize("expr", ["__import__('os')", "a.__dict__", "x._private", "[x for x in y]",
                                  "{k: 1 for k in y}", "(x for x in y)", "(y := 1)", "f(*a)", "f(key=1)",
                                  "math", "xacro.load_yaml.__globals__", "a.gi_frame", "(" * 300 + "1" + ")" * 300,
                                  "-" * 50_000 + "1"])
def test_unsafe_expressions_are_refused(expr: str) -> None:
    with pytest.raises(UnsafeXacro):
        check_expression(expr)


LAUGHS = """<?xml version="1.0"?>
<!DOCTYPE lolz [<!ENTITY lol "lol"><!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
<!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">]>
<robot name="&lol3;" xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="a"/></robot>
"""


@pytest.mark.parametrize("name", ["laughs.urdf", "laughs.sdf", "laughs.urdf.xacro"])
def test_entity_declarations_are_refused_not_hinted_as_unclosed_tag(tmp_path: Path,
                                                                    capsys: pytest.CaptureFixture[str],
                                                                    name: str) -> None:
    path = tmp_path / name
    path.write_text(LAUGHS, encoding="utf-8")
    code, text = _run(["lint", str(path)], capsys)
    assert code == 2 and "DOCTYPE" in text and "unclosed" not in text and "lollol" not in text
    assert text.count("\n") == 1
