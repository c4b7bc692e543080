"""One YAML loader with an alias budget for every reader (before: a 2.6 kB Kalibr camchain whose
``distortion_coeffs`` came from 9 levels of 10 aliases gave no answer in 60 s, stuck in ``as_matrix`` ->
``_flatten``; ``&r [1.0, *r]`` gave exit 3, RecursionError)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from s2r.errors import FormatError, S2RError
from s2r.formats._common import as_matrix
from s2r.safeparse import check_yaml_graph, parse_yaml
from tests.hostile._limits import run_s2r


def _bomb(levels: int, *, header: str = "") -> str:
    lines = [header] if header else []
    lines.append("a0: &a0 [" + ", ".join(f"{k}.0" for k in range(10)) + "]")
    lines += [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]" for i in range(1, levels)]
    lines.append(f"cam0:\n  camera_model: pinhole\n  intrinsics: [400, 400, 320, 240]\n  distortion_model: radtan\n"
                 f"  distortion_coeffs: [{', '.join([f'*a{levels - 1}'] * 10)}]\n  resolution: [640, 480]\n"
                 "cam1:\n  camera_model: pinhole\n  intrinsics: [400, 400, 320, 240]\n  distortion_model: radtan\n"
                 "  distortion_coeffs: [0, 0, 0, 0]\n  resolution: [640, 480]\n"
                 "  T_cn_cnm1: [[1, 0, 0, -0.1], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]")
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("header", ["", "%YAML:1.0"])
def test_an_alias_bomb_is_refused_quickly_naming_the_file(tmp_path: Path, header: str) -> None:
    path = tmp_path / "camchain.yaml"
    path.write_text(_bomb(9, header=header), encoding="utf-8")
    done = run_s2r("profile", "show", str(path))
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert done.stderr.startswith(f"error: {path}") and "alias bomb" in done.stderr


def test_a_recursive_alias_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "camchain.yaml"
    path.write_text("cam0:\n  camera_model: pinhole\n  intrinsics: &r [1.0, *r]\n", encoding="utf-8")
    done = run_s2r("profile", "show", str(path))
    assert done.returncode == 2 and "recursive alias" in done.stderr and str(path) in done.stderr
    with pytest.raises(S2RError, match="recursive alias"):
        parse_yaml("a: &m {b: *m}", path="x.yaml")


def test_aliases_under_the_budget_still_meet_the_shape_check(tmp_path: Path) -> None:
    path = tmp_path / "camchain.yaml"
    path.write_text(_bomb(3), encoding="utf-8")  # 10^4 numbers where 4 are expected
    done = run_s2r("profile", "convert", str(path), "--to", "s2r", "-o", str(tmp_path / "p.yaml"))
    assert done.returncode == 2 and "distortion_coeffs" in done.stderr and "got more" in done.stderr
    assert not (tmp_path / "p.yaml").exists()


def test_legitimate_anchors_and_merge_keys_load() -> None:
    data = parse_yaml("base: &b {fx: 1.0, fy: 2.0}\ncam: {<<: *b, cx: 3.0}\nrows: [&r [1, 2], *r]\n")
    assert data["cam"] == {"fx": 1.0, "fy": 2.0, "cx": 3.0} and data["rows"] == [[1, 2], [1, 2]]


def test_the_graph_check_and_flatten_directly() -> None:
    node = yaml.compose("a: &a [1, 2, 3]\nb: [*a, *a, *a]")
    assert node is not None
    check_yaml_graph(node, limit=30)
    with pytest.raises(yaml.YAMLError, match="alias bomb"):
        check_yaml_graph(node, limit=10)
    looped: list[object] = [1.0]
    looped.append(looped)
    with pytest.raises(FormatError, match="contains itself"):
        as_matrix(looped, (2,), "f.yaml", "D")
    deep: list[object] = [1.0]
    for _ in range(20):
        deep = [deep]
    with pytest.raises(FormatError, match="nested deeper"):
        as_matrix(deep, (1,), "f.yaml", "D")
    empties: list[object] = []
    for _ in range(6):
        empties = [empties] * 40  # 40^6 = 4e9 empty lists within the nesting limit, no number
    with pytest.raises(FormatError, match="got more"):
        as_matrix(empties, (4,), "f.yaml", "D")
    assert as_matrix([[1, 2], [3, 4]], (2, 2), "f.yaml", "K").tolist() == [[1.0, 2.0], [3.0, 4.0]]
