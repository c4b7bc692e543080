"""File names holding ESC, OSC, BEL, CR, LF or C1 controls reach the terminal escaped (``\\x1b``), in error lines,
log lines and anything the CLI prints (before: "skipped ..." lines recoloured and retitled the terminal and
forged output lines; error lines passed ESC and BEL)."""

from __future__ import annotations

import logging
import re
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.errors import S2RError, terminal_safe

HOSTILE = "rig\x1b[31m\x1b]0;pwned\x07\r\nwrote rig.yaml: 24 views used\x9b2J\u202e"
#: Any control character but the newline ending each line.
_CONTROL = re.compile("[\x00-\x09\x0b-\x1f\x7f-\x9f\u202a-\u202e]")


def _clean(stream: str) -> None:
    assert not _CONTROL.search(stream), repr(stream)
    assert "\nwrote rig.yaml: 24" not in stream


def test_terminal_safe_escapes_every_control_and_keeps_the_rest() -> None:
    assert terminal_safe("a\x1bb\nc\x07d\x9be\u202ef") == "a\\x1bb\\nc\\x07d\\x9be\\u202ef"
    assert terminal_safe("température 3 µm") == "température 3 µm"
    assert terminal_safe("a\nb\tc\rd", keep="\n\t") == "a\nb\tc\\rd"


def test_error_lines_escape_the_file_name(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / (HOSTILE + ".yaml")
    bad.write_text("camera_name: [", encoding="utf-8")
    for target in (bad, tmp_path / ("missing" + HOSTILE + ".yaml")):
        assert main(["profile", "show", str(target)]) == 2
        err = capsys.readouterr().err
        _clean(err)
        assert len(err.splitlines()) == 1 and "\\x1b[31m" in err
    assert "\\x07" in S2RError("x", path=HOSTILE).one_line()


def test_printed_output_and_log_lines_escape_names(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / ("out" + HOSTILE.replace("\r\n", "") + ".yaml")
    assert main(["profile", "convert", "realsense_d435_848x480", "--to", "s2r", "-o", str(out)]) == 0
    printed = capsys.readouterr()
    _clean(printed.out)
    assert "\\x1b]0;pwned\\x07" in printed.out and out.exists()
    from s2r.cli import _WarningFormatter

    record = logging.LogRecord("s2r.calib", logging.WARNING, __file__, 1, "%s has no partner image; skipped",
                               (HOSTILE,), None)
    line = _WarningFormatter().format(record)
    _clean(line)
    assert line.startswith("warning: rig\\x1b[31m") and "\\r\\nwrote" in line
