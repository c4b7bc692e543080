"""Resource exhaustion by an allowed xacro expression or macro: the expansion runs in a child process under CPU,
memory and wall-clock limits (s2r/sources/isolation.py), so a hostile file costs seconds and one error line,
never the machine."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.errors import SourceError
from s2r.sources.isolation import Limits, run_limited
from s2r.sources.urdf.xacro import expand_xacro

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="limits need os.fork (POSIX)")


def _xacro(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "bomb.urdf.xacro"
    path.write_text('<?xml version="1.0"?>\n<robot name="bomb" xmlns:xacro="http://www.ros.org/wiki/xacro">\n'
                    f'{body}\n<link name="base_link"/>\n</robot>\n', encoding="utf-8")
    return path


def test_huge_power_is_stopped_by_the_cpu_limit(tmp_path: Path) -> None:
    path = _xacro(tmp_path, '<link name="l${10**10**10}"/>')
    start = time.monotonic()
    with pytest.raises(SourceError, match=r"used more than 1 s of CPU") as info:
        expand_xacro(path, limits=Limits(cpu_s=1, wall_s=60))
    assert time.monotonic() - start < 30
    assert "bomb.urdf.xacro" in str(info.value) and "\n" not in str(info.value)


def test_huge_string_is_stopped_by_the_memory_limit_through_the_cli(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _xacro(tmp_path, '<link name="l${len(\'x\' * 10**11)}"/>')
    out = tmp_path / "p.yaml"
    code = main(["profile", "from-urdf", str(path), "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    assert "MiB of memory" in err and "bomb.urdf.xacro" in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_macro_doubling_is_stopped(tmp_path: Path) -> None:
    """Each macro level calls the one below twice: 2**40 links if nothing stops it."""
    levels = ['<xacro:macro name="m0"><link name="l"/></xacro:macro>']
    levels += [f'<xacro:macro name="m{i}"><xacro:m{i - 1}/><xacro:m{i - 1}/></xacro:macro>' for i in range(1, 41)]
    path = _xacro(tmp_path, "\n".join(levels) + "\n<xacro:m40/>")
    with pytest.raises(SourceError, match=r"xacro expansion stopped: it (used more than|needed more than)"):
        expand_xacro(path, limits=Limits(cpu_s=2, memory_bytes=256 << 20, wall_s=60))


def test_a_normal_xacro_still_expands_and_errors_keep_their_line(tmp_path: Path) -> None:
    good = _xacro(tmp_path, '<xacro:property name="w" value="${2**10}"/><link name="w${w}"/>')
    assert 'name="w1024"' in expand_xacro(good)
    bad = _xacro(tmp_path, '<link name="${undefined_name}"/>')
    with pytest.raises(SourceError, match="xacro expansion failed") as info:
        expand_xacro(bad)
    assert info.value.path == str(bad) and info.value.field == "xacro"


def test_a_blocked_child_is_killed_at_the_wall_clock_limit(tmp_path: Path) -> None:
    start = time.monotonic()
    with pytest.raises(SourceError, match=r"took longer than 0.5 s"):
        run_limited(lambda: time.sleep(30), path=tmp_path / "x.xacro", what="xacro expansion",
                    limits=Limits(wall_s=0.5))
    assert time.monotonic() - start < 10
