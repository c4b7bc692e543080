"""Compressed chunks of ROS 1 bags, bounded before they are inflated.

A ROS 1 bag stores its messages in chunks, optionally compressed (``bz2`` or ``lz4``); each chunk record's header
states the inflated ``size``. rosbags inflates a whole chunk in one call, so an 8 kB chunk of zeros that inflates
to 2 GiB takes 2 GiB (and 4 GB at the peak). Here every chunk of an open rosbags ROS 1 reader is checked when the
bag is opened: a declared size above :data:`MAX_CHUNK_BYTES` is refused at once, and each chunk is later inflated
by a streaming decompressor that stops one byte past the declared size (a chunk whose data inflate to more than its
header states is refused, having cost at most its declared size).

This reaches into rosbags' ROS 1 reader (its ``chunks`` table of ``Chunk(datasize, datapos, decompressor)`` and its
``Header``); tests/recordings/test_bag_chunks.py pins that against the installed rosbags.
"""

from __future__ import annotations

import bz2
from collections.abc import Callable
from pathlib import Path
from typing import Any

from s2r.errors import S2RError

__all__ = ["MAX_CHUNK_BYTES", "bound_ros1_chunks"]

#: Largest inflated ROS 1 chunk read (bytes). A chunk holds at least one message: a raw 16384x16384 mono8 image
#: (the largest s2r reads) is 256 MiB, a 4K BGR image 25 MB; rosbag's default chunk is 768 kB.
MAX_CHUNK_BYTES = 320 << 20
_STEP = 1 << 20


class ChunkTooLarge(Exception):
    """A chunk inflates to more than its bound (raised from inside rosbags' message loop)."""


def _inflater(compression: str) -> Any:
    if compression == "bz2":
        return bz2.BZ2Decompressor()
    import lz4.frame  # type: ignore[import-untyped]  # rosbags' own dependency for lz4 chunks

    return lz4.frame.LZ4FrameDecompressor()


def bounded_decompressor(compression: str, limit: int) -> Callable[[bytes], bytes]:
    """A ``decompress(data) -> bytes`` for ``compression`` ('bz2' or 'lz4') that raises :class:`ChunkTooLarge` as
    soon as the output would pass ``limit`` bytes (never holding more than ``limit`` + 1 MiB)."""

    def decompress(data: bytes) -> bytes:
        inflater = _inflater(compression)
        parts: list[bytes] = []
        total = 0
        part = inflater.decompress(data, max_length=_STEP)
        while True:
            parts.append(part)
            total += len(part)
            if total > limit:
                raise ChunkTooLarge(f"a {compression} chunk inflates to more than the {limit} bytes it declares")
            if inflater.eof or (getattr(inflater, "needs_input", True) and not part):
                break
            part = inflater.decompress(b"", max_length=_STEP)
        return b"".join(parts)

    return decompress


def bound_ros1_chunks(ros1_reader: Any, *, bag: Path, error: type[S2RError], limit: int = MAX_CHUNK_BYTES) -> None:
    """Check every chunk of an open rosbags ROS 1 ``Reader`` (see the module docstring) and replace its
    decompressor by a bounded one; ``error`` naming ``bag`` for a chunk declaring more than ``limit`` bytes."""
    from rosbags.rosbag1.reader import Chunk, Header, RecordType

    for pos, chunk in list(ros1_reader.chunks.items()):
        ros1_reader.bio.seek(pos)
        header = Header.read(ros1_reader.bio, RecordType.CHUNK)
        compression = header.get_string("compression")
        declared = header.get_uint32("size")
        if compression == "none":
            continue
        if declared > limit:
            raise error(f"a {compression} chunk at byte {pos} declares {declared} bytes inflated, more than s2r "
                        f"inflates ({limit} bytes)", path=bag, hint="record with smaller chunks, or it is not a bag")
        ros1_reader.chunks[pos] = Chunk(chunk.datasize, chunk.datapos, bounded_decompressor(compression, declared))
