"""Safe file output: atomic writes, no silent overwrites, content hashes for provenance."""

from __future__ import annotations

import hashlib
import io
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from s2r.errors import OutputExistsError, S2RError

__all__ = [
    "atomic_write_bytes",
    "atomic_write_npy",
    "atomic_write_text",
    "check_output_dir",
    "check_output_free",
    "parse_yaml",
    "prepare_output_dir",
    "read_text_file",
    "sha256_file",
]


def check_output_free(path: str | Path, *, force: bool) -> Path:
    """Raise :class:`OutputExistsError` if ``path`` exists and ``force`` is false; return it as a Path."""
    out = Path(path)
    if out.exists() and not force:
        raise OutputExistsError("already exists; nothing was overwritten", path=out, hint="pass --force to replace it")
    return out


def atomic_write_bytes(path: str | Path, data: bytes, *, force: bool = False) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder and an atomic rename.

    A crash mid-write leaves the old file (or no file), never a truncated one. Refuses to replace an
    existing file unless ``force``.
    """
    out = check_output_free(path, force=force)
    parent = out.parent if str(out.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
        fd, tmp_name = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp", dir=parent)
    except OSError as exc:
        raise S2RError(f"cannot write: {exc.strerror}", path=out, hint="choose a writable location") from exc
    try:
        # mkstemp creates 0600 files; give the output the permissions a plain open() would (0666 & ~umask).
        umask = os.umask(0)
        os.umask(umask)
        os.fchmod(fd, 0o666 & ~umask)
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp_name, out)
    except BaseException:
        Path(tmp_name).unlink(missing_ok=True)
        raise
    return out


def atomic_write_text(path: str | Path, text: str, *, force: bool = False) -> Path:
    """UTF-8 text version of :func:`atomic_write_bytes`."""
    return atomic_write_bytes(path, text.encode("utf-8"), force=force)


def check_output_dir(path: str | Path, *, force: bool) -> Path:
    """Refuse (creating nothing) a non-folder, or a folder that holds files unless ``force``; return the path."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise OutputExistsError("exists and is not a folder", path=out, hint="choose another output folder")
    if out.is_dir() and any(out.iterdir()) and not force:
        raise OutputExistsError(
            "output folder already holds files; nothing was overwritten", path=out, hint="pass --force to reuse it"
        )
    return out


def prepare_output_dir(path: str | Path, *, force: bool) -> Path:
    """Create ``path`` as an output folder after :func:`check_output_dir`; it must end up writable."""
    out = check_output_dir(path, force=force)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise S2RError(f"cannot create folder: {exc.strerror}", path=out, hint="choose a writable location") from exc
    if not os.access(out, os.W_OK):
        raise S2RError("folder is not writable", path=out, hint="choose a writable location")
    return out


def atomic_write_npy(path: str | Path, array: Any, *, force: bool = False) -> Path:
    """Write ``array`` as a ``.npy`` file (no pickles) through :func:`atomic_write_bytes`."""
    buffer = io.BytesIO()
    np.save(buffer, np.asarray(array), allow_pickle=False)
    return atomic_write_bytes(path, buffer.getvalue(), force=force)


def sha256_file(path: str | Path, *, chunk_bytes: int = 1 << 20) -> str:
    """Hex SHA-256 of a file's content, read in chunks (constant memory)."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        while chunk := handle.read(chunk_bytes):
            digest.update(chunk)
    return digest.hexdigest()


def read_text_file(path: str | Path, *, error: type[S2RError] = S2RError) -> str:
    """A file's UTF-8 text; ``error`` (one line naming the file) when it is missing or unreadable."""
    source = Path(path)
    try:
        return source.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise error("file not found", path=source, hint="check the path") from None
    except IsADirectoryError:
        raise error("is a folder, not a file", path=source, hint="pass the file inside it") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"cannot read: {exc}", path=source, hint="is this a text file?") from None


def parse_yaml(text: str, *, path: str | Path | None = None, error: type[S2RError] = S2RError) -> Any:
    """Parse YAML text with the safe loader; ``error`` naming the file and line when it is malformed."""
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}" if mark is not None else None
        problem = getattr(exc, "problem", None) or "not valid YAML"
        raise error(f"malformed YAML: {problem}", path=path, field=where) from None
    except (ValueError, TypeError, AttributeError, OverflowError, RecursionError) as exc:
        # the safe loader's int/float/timestamp constructors raise plain errors on odd scalars (2026-13-45)
        raise error(f"malformed YAML: {exc}", path=path) from None
