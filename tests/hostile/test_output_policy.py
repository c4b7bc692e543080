"""One output policy: no write through a symlinked folder below the output root, multi-file outputs published
whole or not at all, and a full disk (simulated with RLIMIT_FSIZE in a child process) an exit-2 line
``FILE: cannot write: REASON`` with nothing half-published (before: ``render boards -o R --force`` with
``R/left`` a link replaced ``victim/00.png``; ENOSPC/EFBIG were exit 3; ``convert --to ros`` left
``left.yaml`` without ``right.yaml``; ``calibrate --report`` wrote the profile, then failed on the report)."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import pytest

from s2r.calib.solve.synth import write_stereo_set
from s2r.cli import main
from s2r.errors import OutputExistsError, S2RError
from s2r.fileio import TEMP_PREFIX, OutputBatch, atomic_write_text
from tests.conftest import make_rig
from tests.hostile._limits import run_s2r

BOARD = ("--pattern", "9x6", "--square", "0.025")  # the synthetic sets' board (write_stereo_set)


def _victim(tmp_path: Path) -> tuple[Path, dict[str, bytes]]:
    victim = tmp_path / "victim"
    victim.mkdir()
    (victim / "00.png").write_bytes(b"precious")
    (victim / "notes.txt").write_bytes(b"mine")
    return victim, {p.name: p.read_bytes() for p in victim.iterdir()}


def _unchanged(victim: Path, before: dict[str, bytes]) -> None:
    assert {p.name: p.read_bytes() for p in victim.iterdir()} == before


def test_render_boards_never_writes_through_a_symlinked_subfolder(tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    victim, before = _victim(tmp_path)
    out = tmp_path / "R"
    out.mkdir()
    (out / "left").symlink_to(victim)
    code = main(["render", "boards", "realsense_d435_848x480", "-o", str(out), "--views", "2"])
    assert code == 2 and "already holds files" in capsys.readouterr().err
    # --force replaces R whole: the link goes with the old R (removed, never followed), the views go in a new R
    code = main(["render", "boards", "realsense_d435_848x480", "-o", str(out), "--force", "--views", "2"])
    assert code == 0 and (out / "left").is_dir() and not (out / "left").is_symlink()
    _unchanged(victim, before)


def test_a_link_at_any_depth_below_the_root_is_refused(tmp_path: Path) -> None:
    victim, before = _victim(tmp_path)
    root = tmp_path / "out"
    (root / "a").mkdir(parents=True)
    (root / "a" / "b").symlink_to(victim)
    for force in (False, True):
        with pytest.raises(OutputExistsError, match="symbolic link inside the output folder"), \
                OutputBatch(force=force, root=root) as batch:
            batch.add_text(root / "ok.txt", "fine")
            batch.add_text(root / "a" / "b" / "00.png", "evil")
    _unchanged(victim, before)
    assert [p.name for p in root.iterdir()] == ["a"]  # the staged ok.txt was discarded, not published
    with pytest.raises(S2RError, match="leaves the output folder"):
        atomic_write_text(root / "a" / ".." / ".." / "victim" / "x.txt", "evil", root=root)


def test_a_batch_is_published_whole_and_a_failed_move_is_undone(tmp_path: Path,
                                                                monkeypatch: pytest.MonkeyPatch) -> None:
    root = tmp_path / "out"
    root.mkdir()
    (root / "old.txt").write_text("old", encoding="utf-8")
    real_replace = os.replace
    calls = []

    def full_on_second(src: str, dst: str) -> None:
        calls.append(dst)
        if str(dst).endswith("new.txt"):
            raise OSError(errno.ENOSPC, "No space left on device")
        real_replace(src, dst)

    monkeypatch.setattr(os, "replace", full_on_second)
    with pytest.raises(S2RError, match=r"new.txt: cannot write: No space left on device"), \
            OutputBatch(force=True, root=root) as batch:
        batch.add_text(root / "old.txt", "replaced")
        batch.add_text(root / "new.txt", "new")
        batch.publish()
    monkeypatch.undo()
    assert (root / "old.txt").read_text(encoding="utf-8") == "old"  # restored from its backup
    assert sorted(p.name for p in root.iterdir()) == ["old.txt"]


def _no_temporaries(folder: Path) -> None:
    assert not [p for p in folder.rglob("*") if p.name.startswith(TEMP_PREFIX)]


def test_full_disk_on_a_ros_pair_publishes_neither_file(tmp_path: Path) -> None:
    # a file limit one byte under the largest file of the pair lets the smaller ones through and stops that one
    whole = tmp_path / "whole"
    assert run_s2r("profile", "convert", "realsense_d435_848x480", "--to", "ros", "-o", str(whole)).returncode == 0
    limit = max(p.stat().st_size for p in whole.iterdir()) - 1
    out = tmp_path / "ros"
    done = run_s2r("profile", "convert", "realsense_d435_848x480", "--to", "ros", "-o", str(out), file_size=limit)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    errors = [line for line in lines if line.startswith("error: ")]
    assert errors == [lines[-1]] and ".yaml: cannot write: File too large" in errors[0]
    assert not out.exists() or list(out.iterdir()) == []


def test_full_disk_on_a_single_file_is_exit_2(tmp_path: Path) -> None:
    out = tmp_path / "p.yaml"
    done = run_s2r("profile", "convert", "realsense_d435_848x480", "--to", "s2r", "-o", str(out), file_size=100)
    assert done.returncode == 2 and done.stderr.startswith(f"error: {out}: cannot write: File too large")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_full_disk_on_the_calibration_report_leaves_no_profile(tmp_path: Path) -> None:
    # the profile is a few kB, the report with its figures hundreds: a 64 kB limit lets only the profile through
    write_stereo_set(make_rig(name="r", width=320, height=240), tmp_path / "set", views=8, seed=3,
                     supersample=1)
    out, report = tmp_path / "rig.yaml", tmp_path / "report"
    # the first run fills the cache
    assert main(["-q", "calibrate", str(tmp_path / "set"), *BOARD, "-o", str(out), "--jobs", "1"]) == 0
    out.unlink()
    done = run_s2r("-q", "calibrate", str(tmp_path / "set"), *BOARD, "-o", str(out), "--report", str(report),
                   "--jobs", "1", file_size=64 << 10, timeout_s=180)
    assert done.returncode == 2, done.stderr
    assert "index.html: cannot write: File too large" in done.stderr and done.stderr.count("\n") == 1
    assert not out.exists() and not report.exists()  # the report folder it made, empty, is removed (issue 37)
    _no_temporaries(tmp_path)
