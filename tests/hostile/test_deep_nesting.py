"""Deeply nested YAML (50000 open brackets) is one exit-2 line naming the file in every reader, never the
internal-error exit 3 a RecursionError used to give `profile show` (its mono-profile probe parsed YAML itself)."""

from __future__ import annotations

from pathlib import Path

import pytest

from s2r.cli import main


@pytest.mark.parametrize("argv", [
    ["profile", "show", "{deep}"],
    ["profile", "convert", "{deep}", "--to", "ros", "-o", "{out}"],
    ["validate", "{deep}", "--quick", "-o", "{out}"],
])
def test_deep_yaml_is_one_line_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str]) -> None:
    deep = tmp_path / "deep.yaml"
    deep.write_text("name: " + "[" * 50000 + "]" * 50000 + "\n", encoding="utf-8")
    code = main([a.format(deep=deep, out=tmp_path / "out") for a in argv])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "deep.yaml" in err and "malformed YAML" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
