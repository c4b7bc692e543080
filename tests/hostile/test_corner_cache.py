"""The corner cache is untrusted input (before: a symlinked ``rig.yaml.corners`` received 48 JSON files and lost
its own 2-hour-old ``.notes.tmp``; a FIFO entry hung for good, /dev/zero was read until memory ran out; a list
root, a missing status or a bad shape gave exit 3, NaN corners an OpenCV error, huge corners a wrong "left and
right look swapped")."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import numpy as np
import pytest

from s2r.calib.detect import CornerCache, Detection
from s2r.calib.solve.synth import write_stereo_set
from s2r.cli import main
from s2r.targets import CharucoTarget
from tests.conftest import make_rig
from tests.hostile._limits import run_s2r

BOARD = ("--pattern", "9x6", "--square", "0.025")  # the synthetic sets' board (write_stereo_set)

SHA = "cd" * 32
PATTERN = (9, 6)


def _good() -> dict[str, object]:
    corners = [[10.0 + 5 * i, 20.0 + 3 * j] for j in range(6) for i in range(9)]
    return {"status": "ok", "size": [640, 480], "detector": "classic", "detail": "", "corners": corners}


BAD_ENTRIES = {
    "list root": [1, 2, 3],
    "missing status": {k: v for k, v in _good().items() if k != "status"},
    "unknown status": {**_good(), "status": "maybe"},
    "bad corner shape": {**_good(), "corners": [[1.0, 2.0, 3.0]] * 54},
    "flat corners": {**_good(), "corners": list(range(108))},
    "wrong corner count": {**_good(), "corners": _good()["corners"][:10]},  # type: ignore[index]
    "huge corners": {**_good(), "corners": [[1e30, -1e30]] * 54},
    "outside the image": {**_good(), "corners": [[5000.0, 10.0]] * 54},
    "bad size": {**_good(), "size": ["640", None]},
    "ok without corners": {**_good(), "corners": None},
    "string detail": {**_good(), "detail": {"x": 1}},
}


def _entry(cache: CornerCache) -> Path:
    path = cache._file(SHA, PATTERN)
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


def test_a_valid_entry_is_read_back(tmp_path: Path) -> None:
    cache = CornerCache(tmp_path / "c")
    _entry(cache).write_text(json.dumps(_good()), encoding="utf-8")
    hit = cache.get("view", SHA, PATTERN)
    assert isinstance(hit, Detection) and hit.cached and hit.corners is not None and hit.corners.shape == (54, 2)


def test_a_target_entry_round_trips_and_needs_its_ids(tmp_path: Path) -> None:
    target = CharucoTarget(target_type="charuco", squaresX=5, squaresY=4, squareLength=0.04, markerLength=0.03,
                           dictionary="DICT_4X4_50")
    cache = CornerCache(tmp_path / "c", target)
    corners = np.array([[10.0, 20.0], [30.0, 40.0], [50.0, 60.0]], np.float32)  # a cut view: 3 of 12 corners
    cache.put(Detection("v", SHA, "ok", size=(640, 480), corners=corners, ids=np.array([0, 4, 7], np.int32)),
              PATTERN)
    hit = cache.get("view", SHA, PATTERN)
    assert hit is not None and hit.ids is not None and hit.ids.tolist() == [0, 4, 7]
    entry = cache._file(SHA, PATTERN)
    entry.write_text(json.dumps({**json.loads(entry.read_text(encoding="utf-8")), "ids": None}), encoding="utf-8")
    assert cache.get("view", SHA, PATTERN) is None


@pytest.mark.parametrize("kind", sorted(BAD_ENTRIES))
def test_malformed_entries_are_discarded(tmp_path: Path, kind: str) -> None:
    cache = CornerCache(tmp_path / "c")
    _entry(cache).write_text(json.dumps(BAD_ENTRIES[kind]), encoding="utf-8")
    assert cache.get("view", SHA, PATTERN) is None


def test_nan_and_non_json_entries_are_discarded(tmp_path: Path) -> None:
    cache = CornerCache(tmp_path / "c")
    path = _entry(cache)
    path.write_text(json.dumps(_good()).replace("10.0", "NaN", 1), encoding="utf-8")
    assert cache.get("view", SHA, PATTERN) is None
    path.write_bytes(b"[" * 100_000)
    assert cache.get("view", SHA, PATTERN) is None
    path.write_bytes(b"\xff\xfe")
    assert cache.get("view", SHA, PATTERN) is None


@pytest.mark.skipif(not hasattr(os, "mkfifo") or not Path("/dev/zero").exists(), reason="needs FIFOs, /dev/zero")
def test_special_and_linked_entries_are_not_read(tmp_path: Path) -> None:
    cache = CornerCache(tmp_path / "c")
    path = _entry(cache)
    os.mkfifo(path)
    started = time.monotonic()
    assert cache.get("view", SHA, PATTERN) is None and time.monotonic() - started < 5  # no writer: would block
    path.unlink()
    path.symlink_to("/dev/zero")
    assert cache.get("view", SHA, PATTERN) is None
    path.unlink()
    elsewhere = tmp_path / "elsewhere.json"
    elsewhere.write_text(json.dumps(_good()), encoding="utf-8")
    path.symlink_to(elsewhere)
    assert cache.get("view", SHA, PATTERN) is None  # a link is never followed, even to a valid entry


def test_a_symlinked_cache_folder_is_not_used(tmp_path: Path) -> None:
    victim = tmp_path / "victim"
    victim.mkdir()
    notes = victim / ".notes.tmp"
    notes.write_text("mine", encoding="utf-8")
    old = time.time() - 7200
    os.utime(notes, (old, old))
    (victim / f"{SHA}-9x6-v6.json").write_text(json.dumps(_good()), encoding="utf-8")
    before = sorted(p.name for p in victim.iterdir())
    link = tmp_path / "rig.yaml.corners"
    link.symlink_to(victim)
    cache = CornerCache(link)
    cache.put(Detection("v", "ef" * 32, "no_board", size=(640, 480)), PATTERN)
    assert cache.get("view", SHA, PATTERN) is None
    assert sorted(p.name for p in victim.iterdir()) == before and notes.read_text(encoding="utf-8") == "mine"


@pytest.mark.slow
def test_calibrate_through_a_hostile_cache(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """End to end: a FIFO entry and malformed entries are detected again (exit 0, in a bounded child: the FIFO
    used to hang); a symlinked cache folder receives nothing."""
    folder = tmp_path / "set"
    write_stereo_set(make_rig(name="r", width=320, height=240), folder, views=8, seed=3, supersample=1)
    out = tmp_path / "rig.yaml"
    assert main(["-q", "calibrate", str(folder), *BOARD, "-o", str(out), "--jobs", "1"]) == 0
    entries = sorted((tmp_path / "rig.yaml.corners").iterdir())
    assert len(entries) == 16
    entries[0].unlink()
    os.mkfifo(entries[0])
    for path, kind in zip(entries[1:], sorted(BAD_ENTRIES), strict=False):
        path.write_text(json.dumps(BAD_ENTRIES[kind]), encoding="utf-8")
    capsys.readouterr()
    done = run_s2r("-q", "calibrate", str(folder), *BOARD, "-o", str(out), "--jobs", "1", "--force", "--json",
                   timeout_s=60)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["detections_from_cache"] == 16 - 1 - len(BAD_ENTRIES)
    victim = tmp_path / "victim"
    victim.mkdir()
    (tmp_path / "other.yaml.corners").symlink_to(victim)
    assert main(["-q", "calibrate", str(folder), *BOARD, "-o", str(tmp_path / "other.yaml"), "--jobs", "1"]) == 0
    assert list(victim.iterdir()) == [] and (tmp_path / "other.yaml").is_file()
