"""Bounded reads of regular files only (no folder, device, FIFO or socket; no file over its limit), ``.npy``
arrays without pickles, and content hashes for provenance."""

from __future__ import annotations

import contextlib
import errno
import hashlib
import io
import os
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.errors import S2RError

__all__ = ["MAX_NPY_BYTES", "MAX_TEXT_BYTES", "NotARegularFile", "check_regular_file", "read_file_head", "read_npy",
           "read_regular_file", "read_text_file", "sha256_file"]


def sha256_file(path: str | Path, *, chunk_bytes: int = 1 << 20) -> str:
    """Hex SHA-256 of a file's content, read in chunks (constant memory)."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        while chunk := handle.read(chunk_bytes):
            digest.update(chunk)
    return digest.hexdigest()


#: Largest text input read (bytes): calibration and description files are kilobytes; the largest robot
#: descriptions a few megabytes.
MAX_TEXT_BYTES = 64 << 20


class NotARegularFile(ValueError):
    """An input path that is a device, FIFO or socket, or a file over the size limit (the message says which)."""


def read_regular_file(path: str | Path, *, limit: int, dir_fd: int | None = None, follow_links: bool = True
                      ) -> bytes:
    """The bytes of the regular file ``path``, refusing anything that could read forever or block.

    ``/dev/zero`` or ``/dev/urandom`` never end, a FIFO blocks until someone writes: the file is opened without
    blocking and checked with ``fstat`` before a byte is read; a regular file over ``limit`` bytes is refused
    from its size. ``dir_fd`` opens ``path`` relative to an open folder; ``follow_links=False`` refuses a
    symbolic link at ``path`` (OSError) instead of reading its target (for caches confined to one folder).

    Raises:
        NotARegularFile: a device, FIFO or socket, or a file over ``limit`` bytes.
        OSError: missing, unreadable, a folder.
    """
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | (0 if follow_links else getattr(os, "O_NOFOLLOW", 0))
    fd = os.open(path, flags, dir_fd=dir_fd)
    try:
        info = _regular_file_info(fd, path)
        if info.st_size > limit:
            raise NotARegularFile(f"{info.st_size} bytes, over the {limit >> 20} MiB s2r reads for this input")
        with os.fdopen(fd, "rb", closefd=False) as fh:
            # sized from fstat: read(limit + 1) would allocate the whole limit (512 MiB for an image) every call
            data = fh.read(min(info.st_size, limit) + 1)
            if len(data) > info.st_size:  # it grew after fstat: read on to the limit
                data += fh.read(limit + 1 - len(data))
        if len(data) > limit:  # the file grew after fstat: refuse rather than return a cut copy
            raise NotARegularFile(f"over the {limit >> 20} MiB s2r reads for this input (it grew while being read)")
        return data
    finally:
        os.close(fd)


def _kind(mode: int) -> str:
    """What a non-regular file is, in words (``a FIFO``, ``a device``, ``a socket``)."""
    if stat.S_ISFIFO(mode):
        return "a FIFO"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    return "a socket" if stat.S_ISSOCK(mode) else "not a file"


def check_regular_file(path: str | Path) -> None:
    """Check, from ``stat`` alone (nothing opened, so a FIFO cannot block), that ``path`` is a regular file.

    Raises:
        FileNotFoundError: nothing at ``path`` (or a dangling link).
        IsADirectoryError: a folder.
        NotARegularFile: ``is a FIFO, not a regular file`` (or a device, a socket).
    """
    mode = os.stat(path).st_mode
    if stat.S_ISDIR(mode):
        raise IsADirectoryError(errno.EISDIR, "is a folder", str(path))
    if not stat.S_ISREG(mode):
        raise NotARegularFile(f"is {_kind(mode)}, not a regular file")


def _regular_file_info(fd: int, path: str | Path) -> os.stat_result:
    """``fstat`` of the open ``fd``: a folder is IsADirectoryError, a device, FIFO or socket NotARegularFile."""
    info = os.fstat(fd)
    if stat.S_ISDIR(info.st_mode):
        raise IsADirectoryError(errno.EISDIR, "is a folder", str(path))
    if not stat.S_ISREG(info.st_mode):
        raise NotARegularFile("not a regular file (a device, FIFO or socket): s2r reads files only")
    return info


@contextlib.contextmanager
def _open_regular(path: str | Path) -> Iterator[io.BufferedReader]:
    """``path`` opened for reading without blocking (a FIFO cannot hang the open), checked to be a regular file."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    with os.fdopen(fd, "rb") as handle:
        _regular_file_info(fd, path)
        yield handle


def read_file_head(path: str | Path, nbytes: int) -> bytes:
    """The first ``nbytes`` of the regular file ``path`` (all of it when shorter): a header to judge before the
    whole file is read. Opened without blocking; a device, FIFO or socket is :class:`NotARegularFile`."""
    with _open_regular(path) as handle:
        return handle.read(nbytes)


#: Largest ``.npy`` array read (bytes of data): a 4K float64 depth image is 66 MB.
MAX_NPY_BYTES = 256 << 20


def read_npy(path: str | Path, *, limit: int = MAX_NPY_BYTES) -> NDArray[Any]:
    """A ``.npy`` array of plain numbers, checked from its header before any allocation.

    The file must be a regular file (no FIFO or device: opened without blocking, checked with ``fstat``); its
    header (format 1.0 or 2.0) must declare a bool, integer or float dtype (no objects, no pickles), a shape
    whose data is at most ``limit`` bytes, and the file must hold that much data. Only the declared data is
    read, so a sparse multi-gigabyte file with a small header costs nothing.

    Raises:
        NotARegularFile: a device, FIFO or socket.
        ValueError: a malformed header, a refused dtype, a shape over ``limit`` or a truncated file.
        OSError: missing, unreadable, a folder.
    """
    with _open_regular(path) as handle:
        info = os.fstat(handle.fileno())
        version = np.lib.format.read_magic(handle)
        if version == (1, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_1_0(handle)
        elif version == (2, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_2_0(handle)
        else:
            raise ValueError(f".npy format version {version[0]}.{version[1]} is not supported (1.0 or 2.0)")
        if dtype.hasobject or dtype.kind not in "biuf" or dtype.subdtype is not None:
            raise ValueError(f"dtype {dtype} is not plain numbers")
        count = 1
        for side in shape:
            count *= int(side)
        nbytes = count * dtype.itemsize
        if nbytes > limit:
            raise ValueError(f"shape {shape} of {dtype} is {nbytes} bytes, over the {limit >> 20} MiB s2r reads")
        if handle.tell() + nbytes > info.st_size:
            raise ValueError(f"truncated: shape {shape} of {dtype} needs {nbytes} bytes of data")
        buffer = bytearray(nbytes)
        if handle.readinto(buffer) != nbytes:
            raise ValueError("truncated while read")
    array = np.frombuffer(buffer, dtype=dtype)
    return array.reshape(shape, order="F" if fortran else "C")


def read_text_file(path: str | Path, *, error: type[S2RError] = S2RError) -> str:
    """A file's UTF-8 text; ``error`` (one line naming the file) when it is missing, unreadable, not a regular
    file or over :data:`MAX_TEXT_BYTES`."""
    source = Path(path)
    try:
        return read_regular_file(source, limit=MAX_TEXT_BYTES).decode("utf-8")
    except FileNotFoundError:
        raise error("file not found", path=source, hint="check the path") from None
    except IsADirectoryError:
        raise error("is a folder, not a file", path=source, hint="pass the file inside it") from None
    except NotARegularFile as exc:
        raise error(str(exc), path=source, hint="pass a calibration or description file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"cannot read: {exc}", path=source, hint="is this a text file?") from None
