"""Atomic writes: each output goes to a temporary file beside its name and is published whole (one file, or a
batch of files all or none), never overwriting silently; a write error is one line with nothing written. Where
outputs may go is checked by :mod:`s2r.fileio.outputs`."""

from __future__ import annotations

import contextlib
import errno
import io
import os
from pathlib import Path
from typing import Any

import numpy as np

from s2r.errors import OutputExistsError, S2RError
from s2r.fileio.outputs import (
    TEMP_PREFIX,
    _cannot_write,
    _check_below_root,
    _lstat,
    _make_folders,
    _refuse_special,
    check_output_free,
)

__all__ = ["OutputBatch", "atomic_write_bytes", "atomic_write_npy", "atomic_write_text", "npy_bytes"]


def _write_temporary(out: Path, data: bytes, *, sync: bool = True) -> str:
    """Write ``data`` to a new temporary file beside ``out`` (synced to disk unless ``sync`` is False); its name.

    Any failure (no space, file too large, read-only, no permission) removes the temporary and raises the
    one-line ``FILE: cannot write: REASON``.
    """
    import tempfile  # here: only writes need it (its imports cost 3 ms of every command's start-up)

    parent = out.parent if str(out.parent) else Path(".")
    try:
        _make_folders(parent)
        fd, tmp_name = tempfile.mkstemp(prefix=f"{TEMP_PREFIX}{out.name[:96]}.", suffix=".tmp", dir=parent)
    except FileExistsError:
        raise S2RError("is a file, expected a folder", path=parent, hint="choose an output folder") from None
    except OSError as exc:
        raise _cannot_write(out, exc) from None
    try:
        # mkstemp creates 0600 files; give the output the permissions a plain open() would (0666 & ~umask).
        umask = os.umask(0)
        os.umask(umask)
        os.fchmod(fd, 0o666 & ~umask)
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            if sync:
                os.fsync(handle.fileno())
    except OSError as exc:
        Path(tmp_name).unlink(missing_ok=True)
        raise _cannot_write(out, exc) from None
    except BaseException:
        Path(tmp_name).unlink(missing_ok=True)
        raise
    return tmp_name


class OutputBatch:
    """Output files written to temporaries beside their final names, then published together or not at all.

    Use as a context manager: :meth:`add_bytes` / :meth:`add_text` write each file's temporary (a full disk shows
    there, as ``FILE: cannot write: REASON``, before anything is published); :meth:`publish` checks every final
    name again, then moves them all into place. When a move fails, the ones already moved are undone (a
    replaced file is restored from a hard-linked backup). Leaving the block without publishing removes every
    temporary.

    Args:
        force: replace existing regular files (never links, folders or special files).
        root: the output folder; every folder between it and a file must be a real folder (a symlinked
            ``R/left`` is refused), and files outside it are refused.
        durable: sync each file to disk before it is published (False for a cache whose reader rejects a file
            a power loss left empty or torn: it saves a disk flush per file).
    """

    def __init__(self, *, force: bool, root: str | Path | None = None, durable: bool = True) -> None:
        self.force = force
        self.root = None if root is None else Path(root)
        self.durable = durable
        self._staged: list[tuple[str, Path]] = []
        self._names: set[Path] = set()

    def __enter__(self) -> OutputBatch:
        return self

    def __exit__(self, *exc: object) -> None:
        self.discard()

    def _check(self, path: str | Path) -> Path:
        out = Path(path)
        if self.root is not None:
            _check_below_root(self.root, out)
        return check_output_free(out, force=self.force)

    def add_bytes(self, path: str | Path, data: bytes) -> Path:
        """Stage ``data`` for ``path`` (checked now and again at :meth:`publish`); returns ``path``."""
        out = self._check(path)
        if out in self._names:
            raise ValueError(f"{out} is staged twice")
        self._staged.append((_write_temporary(out, data, sync=self.durable), out))
        self._names.add(out)
        return out

    def add_file(self, path: str | Path, source: str | Path) -> Path:
        """Stage the finished file ``source`` for ``path`` (a file a library wrote by name, such as a bag): it is
        moved beside ``path`` now (same filesystem; synced unless ``durable`` is False) and published with the
        rest. ``source`` must be a regular file the caller owns; it is gone afterwards."""
        import tempfile

        out = self._check(path)
        if out in self._names:
            raise ValueError(f"{out} is staged twice")
        tmp_name = ""
        try:
            if self.durable:
                with open(source, "rb") as handle:
                    os.fsync(handle.fileno())
            fd, tmp_name = tempfile.mkstemp(prefix=f"{TEMP_PREFIX}{out.name[:96]}.", suffix=".tmp", dir=out.parent)
            os.close(fd)
            os.replace(source, tmp_name)
        except OSError as exc:
            if tmp_name:
                Path(tmp_name).unlink(missing_ok=True)
            raise _cannot_write(out, exc) from None
        self._staged.append((tmp_name, out))
        self._names.add(out)
        return out

    def add_text(self, path: str | Path, text: str) -> Path:
        """UTF-8 text version of :meth:`add_bytes`."""
        return self.add_bytes(path, text.encode("utf-8"))

    def discard(self) -> None:
        """Remove every temporary not yet published."""
        for tmp_name, _ in self._staged:
            Path(tmp_name).unlink(missing_ok=True)
        self._staged.clear()
        self._names.clear()

    def publish(self) -> list[Path]:
        """Move every staged file into place, all or none; the final paths in the order they were added."""
        if self.root is not None:
            for _, out in self._staged:
                _check_below_root(self.root, out)  # the tree may have changed while the files were written
        done: list[tuple[Path, str | None]] = []
        try:
            for tmp_name, out in self._staged:
                done.append((out, _publish(tmp_name, out, force=self.force)))
        except BaseException:
            _undo(done)
            raise
        for _, backup in done:
            if backup is not None:
                Path(backup).unlink(missing_ok=True)
        published = [out for _, out in self._staged]
        self.discard()
        return published


def _undo(done: list[tuple[Path, str | None]]) -> None:
    """Take back published files: restore each replaced file from its backup, remove each new one."""
    for out, backup in reversed(done):
        with contextlib.suppress(OSError):
            if backup is not None:
                os.replace(backup, out)
            else:
                out.unlink()


def _publish(tmp_name: str, out: Path, *, force: bool) -> str | None:
    """Move the finished temporary file to ``out``: exclusively (hard link) unless ``force``, else by rename;
    the name of a hard-linked backup of the file it replaced (None when there was none).

    Without ``force`` the link fails when ``out`` appeared meanwhile (another run), so of two racing runs at
    most one succeeds. Filesystems without hard links fall back to claiming the name with ``O_EXCL`` first.
    """
    try:
        if force:
            return _replace(tmp_name, out)
        try:
            os.link(tmp_name, out)
        except FileExistsError:
            raise OutputExistsError("already exists (written by another run meanwhile?); nothing was overwritten",
                                    path=out, hint="pass --force to replace it") from None
        except OSError as exc:
            if exc.errno not in (errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EXDEV, errno.EMLINK):
                raise
            try:
                os.close(os.open(out, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600))
            except FileExistsError:
                raise OutputExistsError("already exists (written by another run meanwhile?); nothing was "
                                        "overwritten", path=out, hint="pass --force to replace it") from None
            os.replace(tmp_name, out)
            return None
        os.unlink(tmp_name)
        return None
    except OSError as exc:
        raise _cannot_write(out, exc) from None


def _replace(tmp_name: str, out: Path) -> str | None:
    """``os.replace`` the temporary onto ``out``, keeping a hard-linked backup of a replaced regular file."""
    st = _lstat(out)
    if st is None:
        os.replace(tmp_name, out)
        return None
    _refuse_special(out, st)  # it may have changed since the first check
    backup = f"{tmp_name}.bak"
    try:
        os.link(out, backup)
    except OSError:
        backup = ""
    os.replace(tmp_name, out)
    return backup or None


def atomic_write_bytes(path: str | Path, data: bytes, *, force: bool = False, root: str | Path | None = None,
                       durable: bool = True) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder, published atomically.

    A crash mid-write leaves the old file (or no file), never a truncated one; a write error (full disk, file
    too large, read-only) is ``FILE: cannot write: REASON`` with nothing written. Refuses (see
    :func:`check_output_free`) symlinks and non-regular files always, an existing file unless ``force``; without
    ``force`` the file is created exclusively, so two racing runs cannot both write it. With ``root``, every
    folder between it and ``path`` must be a real folder, not a link. ``durable`` as :class:`OutputBatch`.
    """
    with OutputBatch(force=force, root=root, durable=durable) as batch:
        batch.add_bytes(path, data)
        return batch.publish()[0]


def atomic_write_text(path: str | Path, text: str, *, force: bool = False, root: str | Path | None = None,
                      durable: bool = True) -> Path:
    """UTF-8 text version of :func:`atomic_write_bytes`."""
    return atomic_write_bytes(path, text.encode("utf-8"), force=force, root=root, durable=durable)


def npy_bytes(array: Any) -> bytes:
    """``array`` as the bytes of a ``.npy`` file (no pickles)."""
    buffer = io.BytesIO()
    np.save(buffer, np.asarray(array), allow_pickle=False)
    return buffer.getvalue()


def atomic_write_npy(path: str | Path, array: Any, *, force: bool = False, root: str | Path | None = None) -> Path:
    """Write ``array`` as a ``.npy`` file (no pickles) through :func:`atomic_write_bytes`."""
    return atomic_write_bytes(path, npy_bytes(array), force=force, root=root)
