"""``s2r check`` matches pairs in worker processes (``--jobs``): the same matches, in input order, as one process;
a bad pair met mid-stream still stops the check with its one-line error; progress counts every pair."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.drift.check import match_pairs, run_check
from s2r.drift.source import StereoSource, read_pairs
from s2r.errors import CheckError
from tests.drift.conftest import rig, write_recording


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_recording(tmp_path_factory.mktemp("par") / "rec", rig(), (0.1, 0.0, -0.1), frames=5, seed=3)


def test_pool_matches_equal_one_process_in_input_order(recording: Path) -> None:
    pairs = list(read_pairs(StereoSource(folder=recording)))
    seen: list[tuple[int, int]] = []
    serial = match_pairs(rig(), pairs, jobs=1)
    pooled = match_pairs(rig(), iter(pairs), jobs=2, progress=lambda d, t, _: seen.append((d, t)), total=len(pairs))
    assert [f.name for f in pooled] == [name for name, _, _ in pairs]
    for a, b in zip(serial, pooled, strict=True):
        assert len(a.left) > 20
        np.testing.assert_array_equal(a.left, b.left)
        np.testing.assert_array_equal(a.right, b.right)
        assert a.second is not None and b.second is not None
        np.testing.assert_array_equal(a.second.left, b.second.left)
    assert seen == [(k, len(pairs)) for k in range(1, len(pairs) + 1)]
    one = run_check(rig(), pairs, jobs=1).result.as_dict()
    two = run_check(rig(), pairs, jobs=2).result.as_dict()
    assert one == two


def test_a_wrong_size_pair_mid_stream_stops_the_pooled_check(recording: Path) -> None:
    pairs = list(read_pairs(StereoSource(folder=recording)))
    name, left, right = pairs[3]
    pairs[3] = (name, cv2.resize(left, (240, 180)), right)
    with pytest.raises(CheckError, match="left image is 240x180 px"):
        match_pairs(rig(), iter(pairs), jobs=2)


def test_progress_ends_at_the_pairs_found_when_fewer_than_max_frames(recording: Path) -> None:
    pairs = list(read_pairs(StereoSource(folder=recording)))
    for jobs in (1, 2):
        seen: list[tuple[int, int]] = []
        match_pairs(rig(), iter(pairs), jobs=jobs, progress=lambda d, t, _, into=seen: into.append((d, t)), total=20)
        assert seen[-1] == (len(pairs), len(pairs)) and seen[-2] == (len(pairs), 20)
