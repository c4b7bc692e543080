"""A drift check's StereoSource is a RecordingSpec and a pair count (one type of recording, not a copy of its
fields): built either way it is the same value, it reads the spec's fields through, and it survives pickling as a
fleet sends it to Dask workers; the one every/max_frames rule (``thinned``) never reads past the last kept item."""

from __future__ import annotations

import pickle
from pathlib import Path

import pytest

from s2r.drift.source import StereoSource, read_pairs
from s2r.recordings import RecordingSpec
from s2r.recordings.frames import thinned
from tests.drift.conftest import rig, write_recording


def test_one_recording_type_either_way_and_through_pickle(tmp_path: Path) -> None:
    spec = RecordingSpec(bag=tmp_path / "r.bag", left_topic="/l", right_topic="/r", every=2, max_frames=9)
    by_spec = StereoSource(spec, max_frames=4)
    by_fields = StereoSource(bag=tmp_path / "r.bag", left_topic="/l", right_topic="/r", every=2, max_frames=4)
    assert by_spec == by_fields and hash(by_spec) == hash(by_fields)
    assert isinstance(by_spec.recording, RecordingSpec) and by_spec.recording.max_frames is None  # the spread's
    assert (by_spec.bag, by_spec.left_topic, by_spec.every, by_spec.max_frames) == (tmp_path / "r.bag", "/l", 2, 4)
    assert pickle.loads(pickle.dumps(by_spec)) == by_spec
    assert by_spec.describe() == f"{tmp_path / 'r.bag'} (/l, /r)"
    with pytest.raises(AttributeError):
        _ = by_spec.not_a_field  # type: ignore[attr-defined]


def test_read_pairs_spreads_over_the_recording(tmp_path: Path) -> None:
    folder = write_recording(tmp_path / "rec", rig(), (0.0, 0.0, 0.0), frames=5, seed=3)
    source = pickle.loads(pickle.dumps(StereoSource(folder=folder, max_frames=3)))
    assert [name for name, _, _ in read_pairs(source)] == ["00", "02", "04"]


def test_thinned_keeps_every_nth_and_stops_at_the_last_kept() -> None:
    pulled: list[int] = []

    def items() -> object:
        for k in range(100):
            pulled.append(k)
            yield k

    assert [i for i, _ in thinned(items(), 3, 4)] == [0, 3, 6, 9]
    assert pulled == list(range(10))  # nothing read past item 9
    assert [i for i, _ in thinned(range(7), 2)] == [0, 2, 4, 6]
    assert list(thinned(range(7), 1, 0)) == []
