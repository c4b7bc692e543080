"""Inputs that never end or block: a profile, description or image path that is /dev/zero (through a symlink) or a
FIFO is refused from ``fstat`` before a byte is read (before: `profile show` on a /dev/zero symlink read until
memory ran out, a FIFO blocked forever)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.imageio import decode_image_file

pytestmark = pytest.mark.skipif(not Path("/dev/zero").exists() or not hasattr(os, "mkfifo"),
                                reason="needs /dev/zero and FIFOs (POSIX)")


def _specials(tmp_path: Path, suffix: str) -> list[Path]:
    zero = tmp_path / f"zero{suffix}"
    zero.symlink_to("/dev/zero")
    fifo = tmp_path / f"fifo{suffix}"
    os.mkfifo(fifo)
    return [zero, fifo]


@pytest.mark.parametrize("command", [["profile", "show"], ["lint"], ["profile", "from-urdf"]])
def test_text_inputs_that_never_end_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                command: list[str]) -> None:
    for path in _specials(tmp_path, ".urdf" if command[-1] != "show" else ".yaml"):
        extra = ["-o", str(tmp_path / "p.yaml")] if command[-1] == "from-urdf" else []
        code = main([*command, str(path), *extra])
        err = capsys.readouterr().err
        assert code == 2, err
        assert "not a regular file" in err and path.name in err and len(err.strip().splitlines()) == 1


def test_image_inputs_that_never_end_are_refused(tmp_path: Path) -> None:
    for path in _specials(tmp_path, ".png"):
        image, reason = decode_image_file(path)
        assert image is None and "not a regular file" in reason
