"""Recordings where they live: ``http(s)://``, ``s3://`` and ``file://`` URLs read through fsspec, bounded.

A worker reads a remote recording itself: :func:`list_folder` names a folder's entries, :func:`copy_to` streams
one file into a local copy. Both are bounded like local reads: a file over its limit is refused from its declared
size and again while it streams (a server may lie), a listing is at most :data:`MAX_LISTED` entries, and nothing
but these four schemes is accepted (no fsspec chaining with ``::``, no ``memory://``, no local path hidden in a
URL's options).

HTTP: redirects are never followed (a 3xx is an error naming where it points: give that URL instead), so a server
cannot send the reader anywhere else, local or not; a folder is the server's index page (``python -m http.server``,
nginx ``autoindex``), parsed for links to its direct children. ``s3://`` needs the optional ``s3fs`` package
(``pip install 's2r[s3]'``; credentials as boto's usual environment). ``file://`` reads regular files only.
"""

from __future__ import annotations

import contextlib
import os
import stat
from collections.abc import Iterator
from dataclasses import dataclass
from html.parser import HTMLParser
from pathlib import Path
from typing import Any
from urllib.parse import quote, unquote, urlsplit

from s2r.errors import S2RError

__all__ = ["MAX_INDEX_BYTES", "MAX_LISTED", "SCHEMES", "RemoteEntry", "RemoteError", "copy_to", "is_url",
           "join", "list_folder"]

#: URL schemes a recording may use.
SCHEMES = ("file", "http", "https", "s3")
#: Largest index page of an HTTP folder read (bytes), and most entries one listing returns.
MAX_INDEX_BYTES = 8 << 20
MAX_LISTED = 100_000
_CHUNK = 1 << 20
_HINT = "give an http(s)://, s3:// or file:// URL of the recording"


class RemoteError(S2RError):
    """A remote recording that cannot be read: a refused URL, a missing file, a server error, a size limit."""


@dataclass(frozen=True)
class RemoteEntry:
    """One child of a remote folder: its name (one path component), declared size in bytes (None when not
    known) and whether it is a folder."""

    name: str
    size: int | None
    is_dir: bool


def is_url(text: str) -> bool:
    """Whether ``text`` is written as a URL (``scheme://...``, fsspec chains too), supported or not (see
    :func:`check_url`)."""
    return "://" in text


def check_url(url: str) -> str:
    """``url`` when its scheme is one of :data:`SCHEMES` and it has a host (or a path for ``file``); RemoteError
    naming it otherwise."""
    parts = urlsplit(url)
    if parts.scheme.lower() not in SCHEMES or "::" in url:
        raise RemoteError(f"the scheme {parts.scheme!r} is not read (only {', '.join(SCHEMES)})", path=url, hint=_HINT)
    if parts.scheme.lower() != "file" and not parts.netloc:
        raise RemoteError("has no host", path=url, hint=_HINT)
    if parts.scheme.lower() == "file" and parts.netloc not in ("", "localhost"):
        raise RemoteError("a file:// URL names a local path (file:///abs/path)", path=url, hint=_HINT)
    return url


def join(url: str, *names: str) -> str:
    """``url`` with child ``names`` appended (each one path component, percent-encoded except for ``s3://``,
    whose keys are literal)."""
    base = url if url.endswith("/") else url + "/"
    literal = urlsplit(url).scheme.lower() == "s3"
    return base + "/".join(n.strip("/") if literal else quote(n.strip("/"), safe="") for n in names)


def _filesystem(url: str) -> Any:
    import fsspec

    scheme = urlsplit(url).scheme.lower()
    try:
        if scheme in ("http", "https"):
            return fsspec.filesystem(scheme, allow_redirects=False, skip_instance_cache=True)
        return fsspec.filesystem(scheme)
    except ImportError as exc:
        extra = "s3fs (pip install 's2r[s3]')" if scheme == "s3" else str(exc.name or exc)
        raise RemoteError(f"reading {scheme}:// needs {extra}", path=url, hint="install it on every worker") from None


def _local_path(url: str) -> Path:
    return Path(unquote(urlsplit(url).path))


def _refuse_special(url: str) -> None:
    """A ``file://`` URL must name a regular file (a FIFO would block, a device never end)."""
    try:
        mode = os.stat(_local_path(url)).st_mode
    except FileNotFoundError:
        raise RemoteError("not found", path=url, hint="check the URL") from None
    except OSError as exc:
        raise RemoteError(f"cannot read: {exc.strerror}", path=url, hint="check the URL") from None
    if not stat.S_ISREG(mode):
        raise RemoteError("is not a regular file", path=url, hint="name a recording file")


@contextlib.contextmanager
def _stream(url: str, limit: int) -> Iterator[Iterator[bytes]]:
    """The bytes of the file at ``url`` in chunks, refused past ``limit`` bytes (declared or streamed)."""
    check_url(url)
    scheme = urlsplit(url).scheme.lower()
    if scheme == "file":
        _refuse_special(url)
    fs = _filesystem(url)
    try:
        if scheme.startswith("http"):
            handle = fs.open(url, "rb", block_size=0, size=1)  # a stream: no HEAD first, no range requests
        else:
            handle = fs.open(str(_local_path(url)) if scheme == "file" else url, "rb")
    except FileNotFoundError:
        raise RemoteError("not found", path=url, hint="check the URL") from None
    except Exception as exc:  # aiohttp / botocore errors are not OSError: name them in one line
        raise RemoteError(f"cannot open: {type(exc).__name__}: {' '.join(str(exc).split())[:200]}", path=url,
                          hint="check the URL and that the server answers") from None
    with handle:
        _check_response(url, handle, limit)
        yield _chunks(url, handle, limit)


def _check_response(url: str, handle: Any, limit: int) -> None:
    """An HTTP answer must be 200 (no redirect followed); any declared size must be within ``limit``."""
    response = getattr(handle, "r", None)
    size: Any = None
    if response is not None:
        if 300 <= response.status < 400:
            target = response.headers.get("Location", "?")
            raise RemoteError(f"redirects to {target!r}; redirects are not followed", path=url,
                              hint="give the final URL of the recording")
        if response.status != 200:
            raise RemoteError(f"the server answered {response.status}", path=url, hint="check the URL")
        size = response.headers.get("Content-Length")
    else:
        with contextlib.suppress(Exception):
            size = handle.size
    if size is not None and str(size).isdigit() and int(size) > limit:
        raise RemoteError(f"{int(size)} bytes, over the {limit >> 20} MiB s2r reads for this input", path=url,
                          hint="split the recording, or check that the URL names the right file")


def _chunks(url: str, handle: Any, limit: int) -> Iterator[bytes]:
    total = 0
    while True:
        try:
            chunk = handle.read(_CHUNK)
        except Exception as exc:
            raise RemoteError(f"read failed: {type(exc).__name__}: {' '.join(str(exc).split())[:200]}", path=url,
                              hint="check the server") from None
        if not chunk:
            return
        total += len(chunk)
        if total > limit:
            raise RemoteError(f"over the {limit >> 20} MiB s2r reads for this input (it streamed more than it "
                              "declared)", path=url, hint="check that the URL names the right file")
        yield chunk


def copy_to(url: str, dest: Path, *, limit: int) -> Path:
    """Stream the file at ``url`` into the new local file ``dest`` (at most ``limit`` bytes); ``dest``.

    A partial copy is removed when the read fails."""
    try:
        with _stream(url, limit) as chunks, open(dest, "wb") as out:
            for chunk in chunks:
                out.write(chunk)
    except BaseException:
        dest.unlink(missing_ok=True)
        raise
    return dest


class _Links(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.hrefs: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag == "a":
            self.hrefs.extend(v for k, v in attrs if k == "href" and v)


def _child(href: str) -> RemoteEntry | None:
    """The entry an index page's link names, when it is a direct child (no scheme, host, query, ``..``)."""
    parts = urlsplit(href)
    if parts.scheme or parts.netloc or parts.query or href.startswith(("/", "#", "?")):
        return None
    name = unquote(parts.path)
    is_dir = name.endswith("/")
    name = name.rstrip("/")
    if not name or "/" in name or name in (".", "..") or "\x00" in name:
        return None
    return RemoteEntry(name, None, is_dir)


def _http_listing(url: str) -> list[RemoteEntry]:
    page = b"".join(_read_index(join(url, "")))
    parser = _Links()
    parser.feed(page.decode("utf-8", errors="replace"))
    entries = {e.name: e for e in (_child(h) for h in parser.hrefs) if e is not None}
    return list(entries.values())


def _read_index(url: str) -> Iterator[bytes]:
    with _stream(url, MAX_INDEX_BYTES) as chunks:
        yield from chunks


def list_folder(url: str) -> list[RemoteEntry]:
    """The direct children of the folder at ``url``, sorted by name (at most :data:`MAX_LISTED`)."""
    check_url(url)
    entries = _http_listing(url) if urlsplit(url).scheme.lower().startswith("http") else _fs_listing(url)
    if len(entries) > MAX_LISTED:
        raise RemoteError(f"lists {len(entries)} entries; at most {MAX_LISTED} are read", path=url,
                          hint="split the recording into smaller folders")
    return sorted(entries, key=lambda e: e.name)


def _fs_listing(url: str) -> list[RemoteEntry]:
    fs = _filesystem(url)
    target = str(_local_path(url)) if urlsplit(url).scheme.lower() == "file" else url
    try:
        found = fs.ls(target, detail=True)
    except FileNotFoundError:
        raise RemoteError("folder not found", path=url, hint="check the URL") from None
    except Exception as exc:
        raise RemoteError(f"cannot list: {type(exc).__name__}: {' '.join(str(exc).split())[:200]}", path=url,
                          hint="check the URL and the credentials") from None
    entries = []
    for item in found[: MAX_LISTED + 1]:
        name = str(item.get("name", "")).rstrip("/").rsplit("/", 1)[-1]
        if name and name not in (".", ".."):
            size = item.get("size")
            entries.append(RemoteEntry(name, int(size) if isinstance(size, int) else None,
                                       item.get("type") == "directory"))
    return entries
