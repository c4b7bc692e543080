"""Issue 23: a xacro property (or macro parameter) bound to a function passes the name check of an allowed call
(``len``) but is not that function; the property is refused, and the callee object is checked, not its name."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.errors import SourceError
from s2r.sources.urdf.xacro import expand_xacro
from s2r.sources.urdf.xacro_sandbox import UnsafeXacro, allowed_functions, check_callees

HEAD = '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">\n'


def _xacro(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "r.urdf.xacro"
    path.write_text(HEAD + body + "\n</robot>\n", encoding="utf-8")
    return path


@pytest.mark.parametrize("body", [
    '<xacro:property name="len" value="${\'-\'.join}"/><link name="${len([\'a\', \'b\'])}"/>',
    '<xacro:property name="len" value="${map}"/><link name="${list(len(str, [1, 2]))}"/>',
    '<xacro:property name="len" value="${map}" lazy_eval="false"/><link name="x"/>',
    '<xacro:property name="f" value="${python.len}"/><link name="${f}"/>',
    '<xacro:macro name="m" params="len"><link name="${len([1])}"/></xacro:macro><xacro:m len="${\'-\'.join}"/>',
])
def test_a_property_bound_to_a_function_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                  body: str) -> None:
    path = _xacro(tmp_path, body)
    with pytest.raises(SourceError, match="evaluates to a function") as info:
        expand_xacro(path)
    assert "a-b" not in str(info.value) and "['1', '2']" not in str(info.value)
    assert main(["lint", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "refused" in err


def test_callee_is_checked_by_identity_not_by_name() -> None:
    import xacro

    allowed = allowed_functions(xacro._global_symbols)
    check_callees("len([1]) + math.sqrt(4) + radians(1) + python.sorted([1])[0]", xacro._global_symbols, allowed)
    symbols = {**xacro._global_symbols, "len": "-".join, "sqrt": print}
    with pytest.raises(UnsafeXacro, match="'len' is refused: that name is bound to a builtin_function_or_method"):
        check_callees("len(['a'])", symbols, allowed)
    with pytest.raises(UnsafeXacro, match="'sqrt' is refused"):
        check_callees("sqrt(4)", symbols, allowed)
    math_ns = dict(xacro._global_symbols["math"], sqrt=print)
    with pytest.raises(UnsafeXacro, match=r"'math\.sqrt' is refused"):
        check_callees("math.sqrt(4)", {**xacro._global_symbols, "math": math_ns}, allowed)


def test_ordinary_calls_still_expand(tmp_path: Path) -> None:
    body = ('<xacro:property name="b" value="0.12"/><xacro:property name="n" value="${len([1, 2, 3])}"/>'
            '<link name="l${n}_${int(round(degrees(radians(90))))}_${\'%.4f\' % math.sqrt(b * b)}"/>')
    text = expand_xacro(_xacro(tmp_path, body))
    assert f'name="l3_90_{math.sqrt(0.12 * 0.12):.4f}"' in text
