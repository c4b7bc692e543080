"""What the running command reads, so that no output is ever one of its inputs, even with ``--force``.

Two kinds of input are remembered while a command runs (:func:`protecting_inputs`, the CLI's frame around every
command):

- the paths it was **given** (files, folders, the folder part of a glob; a profile found by name,
  :func:`protect_input`): a folder holding one is never replaced whole;
- the files it **found** inside them and will read (:func:`protect_read_files`): the images of an input folder or
  glob, a bag's storage files, a description's includes. The finders call it as they list the files.

An output file is refused when it is the same file as an input (same device and inode: symlinks and hard links
followed, relative or absolute), whichever is known first: :func:`refuse_input_file` (called by
:func:`s2r.fileio.check_output_free` for an existing output) checks the inputs known so far and claims the output;
:func:`protect_read_files` refuses an input an output has already claimed. Either way nothing is written. Writing a
NEW file into an input folder is not refused.
"""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Iterable, Iterator
from pathlib import Path

from s2r.errors import OutputExistsError

__all__ = ["given_input_at", "held_input", "protect_input", "protect_read_files", "protecting_inputs",
           "refuse_input_file"]

_Key = tuple[int, int]  # (st_dev, st_ino): one file whatever the path, link or hard link that names it


class _Inputs:
    """The inputs of the running command (module docstring); ``active`` only inside :func:`protecting_inputs`."""

    def __init__(self) -> None:
        self.active = False
        self.given: list[Path] = []
        self.files: dict[_Key, Path] = {}  # given and found files, by identity
        self.folders: set[str] = set()  # real paths of the folders holding a found file
        self.claimed: dict[_Key, Path] = {}  # existing files an output will replace
        self._real: dict[str, str] = {}  # folder as listed -> its real path (one realpath per folder, not per file)

    def real_folder(self, folder: str) -> str:
        if folder not in self._real:
            self._real[folder] = os.path.realpath(folder or ".")
        return self._real[folder]


_STATE = _Inputs()
_LOCK = threading.Lock()  # a reader thread may list files while the main thread checks an output


def _key(path: str | os.PathLike[str]) -> _Key | None:
    """The identity of the file at ``path`` (links followed); None when it is not there."""
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return None
    return st.st_dev, st.st_ino


@contextlib.contextmanager
def protecting_inputs(paths: Iterable[str | os.PathLike[str]]) -> Iterator[None]:
    """Within the block, the paths a command was given (every path among its arguments but its outputs) and the
    files found in them (:func:`protect_read_files`) are never written over, nor is a folder holding one replaced
    whole by ``--force`` (``-o data --force`` with ``--left-dir data/left`` would remove the recording). The CLI
    runs every command inside one; outside it nothing is remembered."""
    global _STATE
    with _LOCK:
        _STATE = _Inputs()
        _STATE.active = True
    for given in paths:
        protect_input(given)
    try:
        yield
    finally:
        with _LOCK:
            _STATE = _Inputs()


def protect_input(path: str | os.PathLike[str]) -> None:
    """Add one given input (a file, a folder, or a glob: its folder part), or one found on the way (a profile named
    by ``S2R_PROFILE_PATH``, a fleet file's recordings), to those the running command keeps from being written over
    or replaced."""
    text = os.fspath(path)
    parts = Path(text).parts
    magic = next((k for k, part in enumerate(parts) if any(c in part for c in "*?[")), len(parts))
    if magic < len(parts):  # a glob: its folder part
        path = str(Path(*parts[:magic])) if magic else "."
    if not _STATE.active or not text or not os.path.lexists(path):
        return
    key = _key(path)
    with _LOCK:
        if Path(path) not in _STATE.given:
            _STATE.given.append(Path(path))
        if key is not None and os.path.isfile(path):
            _STATE.files.setdefault(key, Path(path))


def protect_read_files(paths: Iterable[str | os.PathLike[str]]) -> None:
    """Remember the files the running command found in its inputs and will read (an input folder's images, a bag's
    storage files, a description's includes): no output may be one of them.

    Raises:
        OutputExistsError: one of them is an output this command already checked (``-o data/left01.jpg`` with the
            folder ``data`` as input), named with the file it is; nothing was written.
    """
    if not _STATE.active:
        return
    found = []
    for path in paths:
        if (key := _key(path)) is not None:
            folder = os.path.dirname(os.fspath(path))
            found.append((key, Path(path), folder, os.path.islink(path)))
    with _LOCK:
        for key, path, folder, link in found:
            if key in _STATE.claimed:
                raise _is_input(_STATE.claimed[key], path)
            _STATE.files.setdefault(key, path)
            _STATE.folders.add(_STATE.real_folder(folder))
            if link:  # the folder it lives in, too: replacing that one would remove it
                _STATE.folders.add(os.path.dirname(os.path.realpath(path)))


def refuse_input_file(out: Path) -> None:
    """Refuse the existing regular file ``out`` as an output when it is an input of the running command (a given
    or found file, by identity); otherwise remember it, so that finding it later as an input is refused."""
    key = _key(out)
    if key is None or not _STATE.active:
        return
    with _LOCK:
        if key in _STATE.files:
            raise _is_input(out, _STATE.files[key])
        _STATE.claimed.setdefault(key, out)


def _is_input(out: Path, found: Path) -> OutputExistsError:
    same = os.path.abspath(out) == os.path.abspath(found)
    return OutputExistsError(f"is {'' if same else f'{found}, '}an input of this command: nothing was written, "
                             "even with --force", path=out, hint="write the output to a file of its own")


def given_input_at(out: Path) -> Path | None:
    """The given input that ``out`` is (the same file or folder, symlinks followed), if any."""
    resolved = out.resolve()
    return next((p for p in _STATE.given if p.resolve() == resolved), None)


def held_input(folder: Path) -> Path | str | None:
    """An input of the running command that replacing ``folder`` whole would take with it: a given path that is
    ``folder`` or lies below it, or the folder of a found file that does (symlinks followed); None when none."""
    resolved = folder.resolve()
    given = given_input_at(folder) or next((p for p in _STATE.given if resolved in p.resolve().parents), None)
    if given is not None:
        return given
    top = str(resolved)
    prefix = top.rstrip(os.sep) + os.sep
    return next((f for f in sorted(_STATE.folders) if f == top or f.startswith(prefix)), None)
