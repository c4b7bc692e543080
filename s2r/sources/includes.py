"""One include resolver for robot descriptions: where an include URI may point, and how much may be included.

Every reader that follows includes (SDF ``<include><uri>``; an MJCF reader's ``<include file>``) calls
:func:`resolve` for each URI and reads the file through one :class:`IncludeBudget` for the whole expansion:

- **Where.** A URI is ``model://NAME[/PATH]`` (the folder ``NAME`` in the first root that holds one), ``file://PATH``,
  an absolute path, or a path relative to the including file's folder. The resolved file (symlinks followed) must lie
  inside one of ``roots``: the description's folder, the model folders and the ``--package-path`` folders. A
  ``model://`` URI with a ``..`` component is refused as such; any other URI that lands outside every root is refused
  BEFORE anything is looked up there, with one message that is the same whether or not a file exists at that path.
- **How much.** The budget counts include depth across nested resolves (a file that includes itself is named as
  such; a chain deeper than ``max_depth`` is refused), every file read (``max_files``), every byte read
  (``max_bytes``) and every XML element (``max_elements``) over the whole expansion, so 7 levels of 12 includes
  (12^7 files) stop after ``max_files`` reads instead of growing for minutes. Each file is read with
  :func:`s2r.fileio.read_regular_file` (no FIFO, device or over-long file).

Unknown models and web (Fuel) URIs raise :class:`MissingInclude`, which a reader may defer: a world that includes
``model://sun`` need not fail when the cameras asked for are defined inline.

A reader follows its includes like this (one budget for the whole description; run the walk under
:func:`s2r.sources.isolation.run_limited` as :mod:`s2r.sources.sdf.include` does)::

    budget = IncludeBudget()
    with budget.top(main_file):
        ...  # for each include element of a file `current`:
        path = resolve(uri, including_file=current, roots=roots, field=f"<include> line {n}", budget=budget)
        with budget.nested(path, including_file=current, field=...):
            text = budget.read(path, including_file=current, field=...)
            ...  # parse text, follow its own includes with current = path
    budget.included  # every file read, for the provenance

Relative URIs start from ``including_file``'s folder (a format whose includes are relative to the main file passes
the main file).
"""

from __future__ import annotations

import os
import re
import urllib.parse
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from s2r.errors import SourceError
from s2r.fileio import NotARegularFile, check_regular_file, read_regular_file

__all__ = ["CAMERALESS_MODELS", "IncludeBudget", "IncludeNotAFile", "MissingInclude", "is_cameraless", "model_name",
           "resolve", "shown"]

#: Standard Gazebo models that hold no sensor (lights and planes), as normalised by :func:`model_name`.
CAMERALESS_MODELS = frozenset({"sun", "ground_plane", "asphalt_plane"})
_WEB = ("http://", "https://")
_OUTSIDE_HINT = "keep included files inside the description's folder, or pass --package-path with their folder"


class MissingInclude(SourceError):
    """An include that names nothing reachable here: an unknown ``model://`` name, a missing file, a web URI.

    Attributes:
        uri: the include's URI as written.
    """

    def __init__(self, message: str, *, uri: str, path: str | Path | None = None, field: str | None = None,
                 hint: str | None = None) -> None:
        super().__init__(message, path=path, field=field, hint=hint)
        self.uri = uri


class IncludeNotAFile(SourceError):
    """An include that names something that exists but is no regular file: a FIFO, a device, a socket, a folder
    (where a file is due). Never opened: a FIFO would block until someone writes to it."""


def _regular(target: Path, shown_uri: str, including_file: Path, field: str) -> bool:
    """True when ``target`` is a regular file, False when nothing is there; :class:`IncludeNotAFile` otherwise."""
    try:
        check_regular_file(target)
    except (FileNotFoundError, NotADirectoryError):
        return False
    except IsADirectoryError:
        raise IncludeNotAFile(f"include {shown_uri!r} is a folder, not a regular file", path=including_file,
                              field=field, hint="give a file") from None
    except NotARegularFile as exc:
        raise IncludeNotAFile(f"include {shown_uri!r} {exc}", path=including_file, field=field,
                              hint="give a file") from None
    except OSError:
        return False
    return True


def shown(text: str, limit: int = 200) -> str:
    """``text`` (a URI) as it may appear in a message or log line: cut to ``limit`` characters, and quoted with
    escapes (``ascii``) when it holds a character that is not printable (a newline, ESC)."""
    cut = text[:limit]
    return cut if cut.isprintable() else ascii(cut)


def model_name(uri: str) -> str:
    """The model an include URI names, normalised (lower case, ``_`` for spaces and ``-``): ``model://sun`` ->
    ``sun``, ``https://fuel.gazebosim.org/1.0/OpenRobotics/models/Ground Plane/2`` -> ``ground_plane``;
    ``""`` when the URI names no model."""
    text = urllib.parse.unquote(uri.strip())
    if text.startswith("model://"):
        name = text[len("model://"):].strip("/").split("/")[0]
    elif text.startswith(_WEB):
        parts = [p for p in text.split("/") if p]
        lowered = [p.lower() for p in parts]
        name = parts[lowered.index("models") + 1] if "models" in lowered[:-1] else parts[-1]
    else:
        return ""
    return re.sub(r"[\s\-]+", "_", name.strip().lower())


def is_cameraless(uri: str) -> bool:
    """True when ``uri`` names a standard model known to hold no camera (:data:`CAMERALESS_MODELS`)."""
    return model_name(uri) in CAMERALESS_MODELS


def _real(path: Path) -> Path | None:
    """``path`` with symlinks and ``..`` resolved, or None when it cannot be (a NUL byte, a symlink loop)."""
    try:
        return Path(os.path.realpath(path))
    except (OSError, ValueError, RuntimeError):
        return None


def _inside(path: Path | None, roots: Sequence[Path]) -> bool:
    return path is not None and any(path == root or root in path.parents for root in roots)


def _outside(uri: str, including_file: Path, field: str) -> SourceError:
    return SourceError(f"include {uri[:200]!r} points outside the description's folder and the model folders: "
                       "refused", path=including_file, field=field, hint=_OUTSIDE_HINT)


def _model_file(folder: Path, budget: IncludeBudget | None, including_file: Path, field: str) -> Path:
    """The SDF a model folder names in its ``model.config`` (``<sdf>...</sdf>``; default ``model.sdf``)."""
    from s2r.sources.xmlparse import parse_xml

    config = folder / "model.config"
    if config.is_file():
        text = budget.read(config, including_file=including_file, field=field) if budget else ""
        try:
            names = [(n.text or "").strip() for n in parse_xml(text, config).root.iter("sdf")] if text else []
        except SourceError:
            names = []
        for name in names:
            if name and (folder / name).is_file():
                return folder / name
    return folder / "model.sdf"


def resolve(uri: str, *, including_file: Path, roots: Sequence[Path], field: str = "<include>",
            budget: IncludeBudget | None = None, folders: bool = True) -> Path:
    """The file an include ``uri`` names, confined to ``roots`` (module docstring).

    Args:
        uri: as written in the include.
        including_file: the file holding the include (relative URIs start from its folder; errors name it).
        roots: the folders included files may lie in, searched in order for ``model://NAME``.
        field: the element named in errors (``<include> line 12``).
        budget: when given, a ``model.config`` read to find a model's SDF counts against it.
        folders: a folder stands for the model file it holds (SDF); False: a folder is :class:`IncludeNotAFile`
            (MJCF includes and assets are files).

    Raises:
        MissingInclude: an unknown model, a missing file or a web URI.
        SourceError: a ``..`` in a ``model://`` URI, or a file outside every root.
    """
    real_roots = [r for r in (_real(Path(p)) for p in roots) if r is not None]
    text = uri.strip()
    if text.startswith(_WEB):
        raise MissingInclude(f"cannot include {shown(text)}: web (Fuel) models are not downloaded", uri=uri,
                             path=including_file, field=field,
                             hint="download the model and pass its parent folder with --package-path")
    if text.startswith("model://"):
        return _resolve_model(text, including_file, real_roots, field, budget)
    raw = Path(text.removeprefix("file://"))
    target = _real(raw if raw.is_absolute() else including_file.parent / raw)
    if not _inside(target, real_roots):
        raise _outside(uri, including_file, field)
    assert target is not None
    if target.is_dir() and not folders:
        raise IncludeNotAFile(f"include {text[:200]!r} is a folder, not a regular file", path=including_file,
                              field=field, hint="give a file")
    if target.is_dir():
        target = _real(_model_file(target, budget, including_file, field))
        if not _inside(target, real_roots):
            raise _outside(uri, including_file, field)
        assert target is not None
    if not _regular(target, text[:200], including_file, field):
        raise MissingInclude(f"included file {text[:200]!r} not found", uri=uri, path=including_file, field=field,
                             hint="fix the <uri> or pass --package-path with the model folder")
    return target


def _resolve_model(uri: str, including_file: Path, roots: Sequence[Path], field: str,
                   budget: IncludeBudget | None) -> Path:
    parts = [p for p in uri[len("model://"):].split("/") if p]
    if not parts or any(p in ("..", ".") or "\\" in p for p in parts):
        raise SourceError(f"include {uri[:200]!r}: a model:// URI names a model folder, refused with '.', '..' or "
                          "no name", path=including_file, field=field, hint="write model://NAME or model://NAME/FILE")
    head = parts[0]
    for root in roots:
        folder = _real(root / head)
        if folder is None or not folder.is_dir():
            continue
        if not _inside(folder, roots):
            raise _outside(uri, including_file, field)
        target = _real(folder.joinpath(*parts[1:])) if len(parts) > 1 else folder
        if target is not None and target.is_dir():
            target = _real(_model_file(target, budget, including_file, field))
        if not _inside(target, roots):
            raise _outside(uri, including_file, field)
        assert target is not None
        if not _regular(target, uri[:200], including_file, field):
            raise MissingInclude(f"model {head!r} has no file {uri[:200]!r}", uri=uri, path=including_file,
                                 field=field, hint="fix the <uri> or the model's model.config")
        return target
    raise MissingInclude(f"model {head[:100]!r} ({shown(uri)}) not found in any model folder", uri=uri,
                         path=including_file, field=field,
                         hint=f"pass --package-path DIR with the folder holding {shown(head, 100)}/, or set one of "
                              "GZ_SIM_RESOURCE_PATH, IGN_GAZEBO_RESOURCE_PATH, GAZEBO_MODEL_PATH")


@dataclass
class IncludeBudget:
    """Limits of one whole include expansion, and the files it read (in order, each once).

    Attributes:
        max_depth: includes nested deeper than this are refused (counted across nested resolves).
        max_files: files read over the whole expansion (every include counts, repeated ones too).
        max_bytes: bytes read over the whole expansion.
        max_elements: XML elements the included files may hold in all (:meth:`add_elements`).
    """

    max_depth: int = 8
    max_files: int = 256
    max_bytes: int = 2 << 20
    max_elements: int = 100_000
    files: int = 0
    bytes: int = 0
    elements: int = 0
    included: list[Path] = field(default_factory=list)
    _stack: list[Path] = field(default_factory=list)
    _top: int = 0

    @contextmanager
    def top(self, path: Path) -> Iterator[None]:
        """Expand the description ``path`` itself within this block (it counts for cycles, not for depth)."""
        self._top = 1
        with self.nested(path, including_file=path, field=""):
            yield

    @contextmanager
    def nested(self, path: Path, *, including_file: Path, field: str) -> Iterator[None]:
        """Expand ``path``'s own includes within this block: one level deeper, refused in a cycle or too deep."""
        path = Path(os.path.realpath(path))
        if path in self._stack:
            loop = " -> ".join(p.name for p in self._stack[self._stack.index(path):])
            raise SourceError(f"{path.name} includes itself (through {loop})", path=including_file, field=field,
                              hint="remove the include that loops back")
        if len(self._stack) >= self.max_depth + self._top:
            raise SourceError(f"includes nested more than {self.max_depth} deep", path=including_file, field=field,
                              hint="flatten the include chain")
        self._stack.append(path)
        try:
            yield
        finally:
            self._stack.pop()

    def add_elements(self, count: int, *, including_file: Path, field: str) -> None:
        """Count ``count`` more XML elements brought in by an include; SourceError past ``max_elements``."""
        self.elements += count
        if self.elements > self.max_elements:
            raise SourceError(f"the included files hold more than {self.max_elements} XML elements",
                              path=including_file, field=field, hint="include smaller models")

    def read(self, path: Path, *, including_file: Path, field: str) -> str:
        """``path``'s text, counted against the budget; SourceError when a limit is passed or it is unreadable."""
        self.files += 1
        if self.files > self.max_files:
            raise SourceError(f"more than {self.max_files} included files in one description (includes fanning "
                              "out?)", path=including_file, field=field, hint="include each model fewer times")
        left = self.max_bytes - self.bytes
        try:
            data = read_regular_file(path, limit=max(left, 0))
        except NotARegularFile as exc:
            raise SourceError(f"included file {path.name!r}: {exc}", path=including_file, field=field,
                              hint=f"the includes of one description may read {self.max_bytes >> 20} MiB in all"
                              ) from None
        except OSError as exc:
            raise SourceError(f"cannot read included file {path.name!r}: {exc.strerror or exc}", path=including_file,
                              field=field, hint="check the file's permissions") from None
        self.bytes += len(data)
        if path not in self.included:
            self.included.append(path)
        try:
            return data.decode("utf-8")
        except UnicodeDecodeError:
            raise SourceError(f"included file {path.name!r} is not UTF-8 text", path=including_file,
                              field=field, hint="include an SDF file") from None
