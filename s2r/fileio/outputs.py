"""Where s2r may write: output files and folders checked before anything is written (no symlink, folder, device,
FIFO or socket where a file goes; no silent overwrite), folders created on the way remembered so a failed run
removes them again, an output folder replaced with ``--force`` restored when the run fails, and never one that
holds an input of the command. Writing itself is :mod:`s2r.fileio.atomic`."""

from __future__ import annotations

import contextlib
import logging
import os
import shlex
import stat
import threading
from collections.abc import Iterator
from pathlib import Path

from s2r.errors import OutputExistsError, S2RError
from s2r.fileio.inputs import held_input, refuse_input_file

log = logging.getLogger(__name__)

__all__ = ["TEMP_PREFIX", "check_output_dir", "check_output_free", "discard_on_failure", "prepare_output_dir",
           "removing_new_folders_on_failure", "warn_leftovers"]


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
    with _SCAN_LOCK:
        _SCANNED.clear()  # each command reports what it finds beside its own outputs
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
    (``--force`` never replaces them), a path under a file, and a file the running command reads (given, or found
    in an input folder: :mod:`s2r.fileio.inputs`). Refused unless ``force``: an existing file.
    """
    out = Path(path)
    warn_leftovers(out.parent)
    st = _lstat(out)
    if st is None:
        return out
    _refuse_special(out, st)
    refuse_input_file(out)  # even with --force: a file this command reads (given, or found in an input folder)
    if not force:
        raise OutputExistsError("already exists; nothing was overwritten", path=out, hint="pass --force to replace it")
    return out


#: Every temporary file or folder s2r creates starts with this: clean-ups only ever touch such names.
TEMP_PREFIX = ".s2r-tmp-"


#: Folders already searched for leftovers by this command (:func:`warn_leftovers`), so a folder of 10,000 frames
#: is listed once, not once per frame.
_SCANNED: set[Path] = set()
_SCAN_LOCK = threading.Lock()


def warn_leftovers(folder: Path) -> None:
    """Warn, in one line, about ``.s2r-tmp-*`` entries in ``folder`` that no run of this process made: a run
    killed by SIGKILL or a power loss leaves its temporaries (``*.tmp``) and, under ``--force``, the previous
    output folder it moved aside (``*.old``). They are never removed here: a concurrent run may own them."""
    key = Path(os.path.abspath(folder))
    with _SCAN_LOCK:
        if key in _SCANNED:
            return
        _SCANNED.add(key)
    try:
        names = sorted(e.name for e in os.scandir(folder) if e.name.startswith(TEMP_PREFIX))
    except OSError:
        return
    own = {old.name for undo in _NEW_FOLDERS for _, old in undo.replaced}
    notes = []
    for name in (n for n in names if n not in own):
        entry = folder / name
        if name.endswith(".old") and entry.is_dir() and not entry.is_symlink():
            output = folder / name[len(TEMP_PREFIX):].rsplit(".", 2)[0]
            notes.append(f"{entry}: left by an interrupted s2r run (the previous {output.name}, moved aside by "
                         f"--force): move it back with `mv {shlex.quote(str(entry))} {shlex.quote(str(output))}` "
                         f"(once no {output.name} is there) or delete it")
        else:
            notes.append(f"{entry}: left by an interrupted s2r run (a temporary): safe to delete")
    if notes:  # one line; a concurrent run may own them, hence no removal
        log.warning("%s (unless another s2r run is writing there now; nothing was removed)", "; ".join(notes))


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


def check_output_dir(path: str | Path, *, force: bool) -> Path:
    """Refuse (creating nothing) a symlink or non-folder, or a folder that holds files unless ``force``. Leftovers
    of an interrupted run beside the folder or in it are reported (:func:`warn_leftovers`)."""
    out = Path(path)
    warn_leftovers(out.parent)
    st = _lstat(out)
    if st is None:
        return out
    if stat.S_ISLNK(st.st_mode):
        raise OutputExistsError("is a symbolic link; s2r does not write through links", path=out,
                                hint="give the link's target folder itself, or another name")
    if not stat.S_ISDIR(st.st_mode):
        raise OutputExistsError("is a file, expected a folder; nothing was written", path=out,
                                hint="choose another output folder")
    if not force:  # with --force the folder is replaced whole, or its files checked one by one
        warn_leftovers(out)
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
    held = held_input(out)
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
