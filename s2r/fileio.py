"""Safe file input and output: bounded reads of regular files only, atomic writes, no silent overwrites,
content hashes for provenance. Parsing YAML and XML is :mod:`s2r.safeparse`."""

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

from s2r.errors import OutputExistsError, S2RError

__all__ = [
    "MAX_NPY_BYTES",
    "MAX_TEXT_BYTES",
    "TEMP_PREFIX",
    "NotARegularFile",
    "OutputBatch",
    "atomic_write_bytes",
    "atomic_write_npy",
    "atomic_write_text",
    "check_output_dir",
    "check_output_free",
    "discard_on_failure",
    "npy_bytes",
    "prepare_output_dir",
    "protect_inputs",
    "read_file_head",
    "read_npy",
    "read_regular_file",
    "read_text_file",
    "removing_new_folders_on_failure",
    "sha256_file",
]

class _FailureUndo:
    """What one :func:`removing_new_folders_on_failure` block undoes on failure, or finishes on success."""

    def __init__(self) -> None:
        self.made: list[Path] = []  # new folders: removed when still empty
        self.trees: list[Path] = []  # folders this run created and filled (a cache): removed whole
        self.replaced: list[tuple[Path, Path]] = []  # (output folder, the old one moved aside beside it)


#: One entry per active :func:`removing_new_folders_on_failure` block, innermost last.
_NEW_FOLDERS: list[_FailureUndo] = []


@contextlib.contextmanager
def removing_new_folders_on_failure() -> Iterator[None]:
    """Within the block, output folders created here (:func:`prepare_output_dir`, an :class:`OutputBatch`'s
    subfolders) are remembered; when the block ends with an exception (bad input found after ``-o DIR`` was
    prepared, Ctrl-C, SIGTERM), those still empty are removed again, deepest first, so a refused run leaves
    nothing behind and its rerun is not refused; folders given to :func:`discard_on_failure` are removed whole.
    An output folder replaced with ``--force`` (:func:`prepare_output_dir`) is restored: the new one is removed
    and the old one moved back; when the block ends normally the old one is removed. The CLI runs every command
    inside one."""
    undo = _FailureUndo()
    _NEW_FOLDERS.append(undo)
    try:
        yield
    except BaseException:
        for tree in reversed(undo.trees):
            _remove_tree(tree)
        for folder in reversed(undo.made):
            with contextlib.suppress(OSError):
                folder.rmdir()  # only an empty folder: published files keep theirs
        for out, old in reversed(undo.replaced):
            _remove_tree(out)
            with contextlib.suppress(OSError):
                os.rename(old, out)
        raise
    else:
        for _, old in undo.replaced:
            _remove_tree(old)
    finally:
        _NEW_FOLDERS.remove(undo)


def discard_on_failure(folder: str | Path) -> None:
    """Remove ``folder`` whole (it must be one this run creates, such as a cache) if the enclosing
    :func:`removing_new_folders_on_failure` block fails: a failed run leaves nothing it created."""
    if _NEW_FOLDERS:
        _NEW_FOLDERS[-1].trees.append(Path(folder))


def _remove_tree(path: Path) -> None:
    """Remove ``path`` and everything below it (a link is removed, never followed); quiet when it is gone."""
    import shutil

    with contextlib.suppress(OSError):
        if path.is_symlink() or not path.is_dir():
            path.unlink()
        else:
            shutil.rmtree(path)


def _make_folders(folder: Path, *, exist_ok: bool = True) -> None:
    """``folder.mkdir(parents=True, exist_ok=exist_ok)``, remembering each folder it created (see
    :func:`removing_new_folders_on_failure`)."""
    missing = [p for p in (folder, *folder.parents) if not os.path.lexists(p)]
    folder.mkdir(parents=True, exist_ok=exist_ok)
    if _NEW_FOLDERS:
        _NEW_FOLDERS[-1].made.extend(reversed(missing))


def _lstat(path: Path) -> os.stat_result | None:
    """``os.lstat`` of ``path`` (the link itself, never its target); None when nothing is there.

    A path whose parent is a file ("out.png/disparity.npy") is refused here, naming that parent.
    """
    try:
        return os.lstat(path)
    except FileNotFoundError:
        return None
    except NotADirectoryError:
        parent = next((p for p in path.parents if p.exists() and not p.is_dir()), path.parent)
        raise S2RError(f"cannot create folder: {parent} is a file, expected a folder", path=path,
                       hint="choose an output folder") from None
    except OSError as exc:
        raise S2RError(f"cannot inspect output: {exc.strerror}", path=path, hint="choose another location") from None


def _refuse_special(out: Path, st: os.stat_result) -> None:
    """Refuse a symlink, folder, device node, FIFO or socket where a regular output file should be."""
    mode = st.st_mode
    if stat.S_ISLNK(mode):
        raise OutputExistsError("is a symbolic link; s2r does not write through links, nothing was written",
                                path=out, hint="give the link's target path itself, or another name")
    if stat.S_ISDIR(mode):
        raise OutputExistsError("is a folder, expected a file; nothing was written", path=out,
                                hint="give a file name inside it")
    if not stat.S_ISREG(mode):
        raise OutputExistsError("is not a regular file (a device, FIFO or socket); nothing was written, even "
                                "with --force", path=out, hint="choose a regular file name")


def check_output_free(path: str | Path, *, force: bool) -> Path:
    """Return ``path`` as a Path if s2r may write a regular file there; :class:`OutputExistsError` otherwise.

    Refused always: a symlink, a folder, a device node (``/dev/null``), a FIFO or a socket at ``path``
    (``--force`` never replaces them), and a path under a file. Refused unless ``force``: an existing file.
    """
    out = Path(path)
    st = _lstat(out)
    if st is None:
        return out
    _refuse_special(out, st)
    if not force:
        raise OutputExistsError("already exists; nothing was overwritten", path=out, hint="pass --force to replace it")
    return out


#: Every temporary file or folder s2r creates starts with this: clean-ups only ever touch such names.
TEMP_PREFIX = ".s2r-tmp-"


def _cannot_write(out: Path, exc: OSError) -> S2RError:
    """The one-line error of a failed write (ENOSPC, EFBIG, EROFS, EACCES...): ``FILE: cannot write: REASON``."""
    reason = exc.strerror or str(exc)
    return S2RError(f"cannot write: {reason}; nothing was written", path=out,
                    hint="free some space or choose a writable location")


def _check_below_root(root: Path, out: Path) -> None:
    """Refuse ``out`` unless every folder between ``root`` (exclusive) and ``out`` is missing or a real folder.

    A symlink there (``R/left`` -> elsewhere) would carry the write outside the output: refused, even with
    ``--force``. Missing folders are created one by one, each checked again after its creation.
    """
    try:
        rel = out.relative_to(root)
    except ValueError:
        raise S2RError("is outside the output folder", path=out, hint=f"write inside {root}") from None
    if len(rel.parts) > 1 and _lstat(root) is None:
        try:
            _make_folders(root)
        except OSError as exc:
            raise _cannot_write(root, exc) from None
    current = root
    for part in rel.parts[:-1]:
        if part in ("..", "."):
            raise S2RError("leaves the output folder", path=out, hint=f"write inside {root}")
        current = current / part
        st = _lstat(current)
        if st is None:
            try:
                _make_folders(current, exist_ok=False)
            except FileExistsError:
                pass
            except OSError as exc:
                raise _cannot_write(current, exc) from None
            st = _lstat(current)
        if st is None or stat.S_ISLNK(st.st_mode):
            raise OutputExistsError("is a symbolic link inside the output folder; s2r does not write through links, "
                                    "nothing was written, even with --force", path=current,
                                    hint="remove the link or choose another output folder")
        if not stat.S_ISDIR(st.st_mode):
            raise OutputExistsError("is a file, expected a folder; nothing was written", path=current,
                                    hint="choose another output folder")


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


def check_output_dir(path: str | Path, *, force: bool) -> Path:
    """Refuse (creating nothing) a symlink or non-folder, or a folder that holds files unless ``force``."""
    out = Path(path)
    st = _lstat(out)
    if st is None:
        return out
    if stat.S_ISLNK(st.st_mode):
        raise OutputExistsError("is a symbolic link; s2r does not write through links", path=out,
                                hint="give the link's target folder itself, or another name")
    if not stat.S_ISDIR(st.st_mode):
        raise OutputExistsError("is a file, expected a folder; nothing was written", path=out,
                                hint="choose another output folder")
    if any(out.iterdir()) and not force:
        raise OutputExistsError(
            "output folder already holds files; nothing was overwritten", path=out, hint="pass --force to reuse it"
        )
    return out


def prepare_output_dir(path: str | Path, *, force: bool, replace: bool = True) -> Path:
    """Create ``path`` as an output folder after :func:`check_output_dir`; it must end up writable.

    Without ``force`` a folder that did not exist is created exclusively: when another run creates it between
    the check and the ``mkdir``, this one stops instead of sharing it. With ``force`` (and ``replace``) a folder
    that holds anything is REPLACED whole, never merged with (an old frame or bag file would stay beside the new
    ones): it is moved aside (renamed to a ``.s2r-tmp-`` name beside it, the same filesystem) and a new empty
    folder takes its name; inside a :func:`removing_new_folders_on_failure` block (every CLI command) the old
    one is removed only when the command has succeeded, and moved back when it fails; outside a block it is
    removed at once. The working folder, the home folder or a filesystem root is never replaced.
    ``replace=False`` writes named files into an existing folder that s2r does not own (``force`` then only
    lets them be overwritten).
    """
    out = check_output_dir(path, force=force)
    st = _lstat(out)
    if force and replace and st is not None and any(out.iterdir()):
        _move_aside(out)
        st = None
    existed = st is not None
    try:
        _make_folders(out.parent)
        _make_folders(out, exist_ok=force or existed)
    except FileExistsError:
        raise OutputExistsError("was created by another run meanwhile; nothing was overwritten", path=out,
                                hint="pass --force to reuse it") from None
    except OSError as exc:
        raise S2RError(f"cannot create folder: {exc.strerror}", path=out, hint="choose a writable location") from exc
    if not os.access(out, os.W_OK):
        raise S2RError("folder is not writable", path=out, hint="choose a writable location")
    return out


#: Paths the running command was given (its inputs, see :func:`protect_inputs`): a folder holding one is never
#: replaced whole.
_INPUTS: list[Path] = []


def protect_inputs(paths: list[str | os.PathLike[str]]) -> None:
    """Remember the paths a command was given (files, folders, the folder part of a glob): ``--force`` then never
    replaces an output folder that holds one of them (``-o data --force`` with ``--left-dir data/left`` would
    remove the recording). The CLI calls it with every path among a command's arguments."""
    _INPUTS.clear()
    for given in paths:
        text = str(given)
        parts = Path(text).parts
        magic = next((k for k, part in enumerate(parts) if any(c in part for c in "*?[")), len(parts))
        if magic < len(parts):  # a glob: its folder part
            text = str(Path(*parts[:magic])) if magic else "."
        if text and os.path.lexists(text):
            _INPUTS.append(Path(text))


def _move_aside(out: Path) -> None:
    """Rename the output folder ``out`` to a new ``.s2r-tmp-NAME.*.old`` folder beside it (see
    :func:`prepare_output_dir`); refuse one whose removal would take more than an output with it."""
    import tempfile

    resolved = out.resolve()
    guarded = {Path.home().resolve(), Path.cwd().resolve()}
    if resolved in guarded or resolved == Path(resolved.anchor) or resolved in Path.cwd().resolve().parents:
        raise OutputExistsError("is the working folder, the home folder, a parent of the working folder or a "
                                "filesystem root: --force would replace it whole; nothing was written", path=out,
                                hint="give a folder of its own to the output, e.g. -o out/depth")
    held = next((p for p in _INPUTS if resolved in p.resolve().parents), None)
    if held is not None:
        raise OutputExistsError(f"holds {held}, an input of this command: --force would replace the folder whole; "
                                "nothing was written", path=out, hint="write the output to a folder of its own")
    old = ""
    try:
        old = tempfile.mkdtemp(prefix=f"{TEMP_PREFIX}{out.name[:96]}.", suffix=".old", dir=out.parent)
        os.rename(out, old)  # onto the new empty folder: one atomic rename
    except OSError as exc:
        if old:
            with contextlib.suppress(OSError):
                os.rmdir(old)
        raise S2RError(f"cannot replace the output folder: {exc.strerror}; nothing was changed", path=out,
                       hint="check the permissions of its parent folder") from None
    if _NEW_FOLDERS:
        _NEW_FOLDERS[-1].replaced.append((out, Path(old)))
    else:
        _remove_tree(Path(old))


def npy_bytes(array: Any) -> bytes:
    """``array`` as the bytes of a ``.npy`` file (no pickles)."""
    buffer = io.BytesIO()
    np.save(buffer, np.asarray(array), allow_pickle=False)
    return buffer.getvalue()


def atomic_write_npy(path: str | Path, array: Any, *, force: bool = False, root: str | Path | None = None) -> Path:
    """Write ``array`` as a ``.npy`` file (no pickles) through :func:`atomic_write_bytes`."""
    return atomic_write_bytes(path, npy_bytes(array), force=force, root=root)


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
