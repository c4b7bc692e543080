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


def test_a_file_that_grows_while_read_is_read_whole_or_refused(tmp_path: Path,
                                                               monkeypatch: pytest.MonkeyPatch) -> None:
    """The read is sized from ``fstat`` (not the limit, which would allocate 512 MiB per image); a file longer
    than ``fstat`` said (it grew in between) is read on, whole up to the limit and refused beyond it."""
    from s2r import fileio

    path = tmp_path / "growing.bin"
    path.write_bytes(bytes(range(256)) * 4)
    real_fstat = os.fstat

    def stale_fstat(fd: int) -> os.stat_result:  # the size before the file grew to 1024 bytes
        info = list(real_fstat(fd))
        info[6] = 10  # st_size
        return os.stat_result(info)

    monkeypatch.setattr(os, "fstat", stale_fstat)  # the os module every reader uses
    assert fileio.read_regular_file(path, limit=4096) == bytes(range(256)) * 4
    with pytest.raises(fileio.NotARegularFile, match="grew while being read"):
        fileio.read_regular_file(path, limit=100)
    monkeypatch.undo()
    assert fileio.read_regular_file(path, limit=1024) == bytes(range(256)) * 4
    with pytest.raises(fileio.NotARegularFile, match="over the"):
        fileio.read_regular_file(path, limit=1023)
