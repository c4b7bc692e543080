"""ROS 1 bags whose bz2/lz4 chunks inflate to more than they may: refused before (or while) inflating, in one line.

Pins the rosbags internals s2r.recordings.bagchunks relies on (the ROS 1 reader's chunks table and Header)."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from s2r.errors import RecordingError
from s2r.recordings import open_recording
from s2r.recordings.bagchunks import bound_ros1_chunks, bounded_decompressor
from s2r.recordings.bags import open_bag
from tests.recordings.helpers import write_bag

pytest.importorskip("rosbags")


def _pairs(n: int = 3) -> list[tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(7)
    return [(rng.integers(0, 255, (48, 64), dtype=np.uint8), rng.integers(0, 255, (48, 64), dtype=np.uint8))
            for _ in range(n)]


@pytest.mark.parametrize("compression", ["bz2", "lz4"])
def test_compressed_chunks_read_whole_when_honest(tmp_path: Path, compression: str) -> None:
    pairs = _pairs()
    bag = write_bag(tmp_path / "c.bag", pairs, compression=compression)
    frames = list(open_recording(bag=bag, left_topic="/l", right_topic="/r", grey=True).frames())
    assert len(frames) == 3 and np.array_equal(frames[2].left, pairs[2][0]) and np.array_equal(frames[2].right,
                                                                                              pairs[2][1])


@pytest.mark.parametrize("compression", ["bz2", "lz4"])
def test_chunk_declaring_more_than_the_bound_is_refused_at_open(tmp_path: Path, compression: str) -> None:
    bag = write_bag(tmp_path / "c.bag", _pairs(), compression=compression)
    reader = open_bag(bag, error=RecordingError)
    try:
        with pytest.raises(RecordingError, match=f"c.bag: a {compression} chunk at byte \\d+ declares \\d+ bytes "
                                                 "inflated, more than s2r inflates \\(1000 bytes\\)"):
            bound_ros1_chunks(reader.readers[0], bag=bag, error=RecordingError, limit=1000)
    finally:
        reader.close()


def _lie_about_size(bag: Path, factor: float) -> None:
    """Rewrite every chunk header's ``size`` field (the inflated size) to ``factor`` x the truth."""
    data = bytearray(bag.read_bytes())
    pos = 0
    while (pos := data.find(b"size=", pos)) >= 0:
        (true,) = struct.unpack_from("<I", data, pos + 5)
        struct.pack_into("<I", data, pos + 5, int(true * factor))
        pos += 9
    bag.write_bytes(bytes(data))


@pytest.mark.parametrize("compression", ["bz2", "lz4"])
def test_chunk_inflating_past_its_declared_size_stops_there(tmp_path: Path, compression: str) -> None:
    bag = write_bag(tmp_path / "c.bag", _pairs(), compression=compression)
    _lie_about_size(bag, 0.25)
    with pytest.raises(RecordingError, match=f"c.bag: cannot read the bag's messages: a {compression} chunk inflates "
                                             "to more than the \\d+ bytes it declares"):
        list(open_recording(bag=bag, left_topic="/l", right_topic="/r").frames())


def test_bounded_decompressor_holds_at_most_the_limit() -> None:
    import bz2

    bomb = bz2.compress(bytes(64 << 20))  # 64 MiB of zeros in ~50 bytes
    assert len(bomb) < 200
    with pytest.raises(Exception, match="inflates to more than the 1000000 bytes"):
        bounded_decompressor("bz2", 1_000_000)(bomb)
    assert bounded_decompressor("bz2", 64 << 20)(bomb) == bytes(64 << 20)
