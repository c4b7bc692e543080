"""xacro expansion through the ``xacro`` package, with ``$(find pkg)`` resolved from package folders.

ROS resolves ``$(find pkg)`` through ament_index (ROS 2) or rospack (ROS 1), neither of which exists
outside a ROS install; here a package is looked up in the ``--package-path`` folders given, then in the
``ROS_PACKAGE_PATH`` environment variable: a folder named ``pkg`` (or holding a ``package.xml`` whose
``<name>`` is ``pkg``) directly in, or up to three levels below, one of those folders.

Expansion runs inside :func:`s2r.sources.urdf.xacro_sandbox.sandbox`: expressions are checked before xacro
evaluates them, files are read only from the description's package and the package folders, and the
environment is never read (see that module for what is allowed).
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from s2r.errors import SourceError
from s2r.fileio import MAX_TEXT_BYTES, read_regular_file
from s2r.sources.isolation import Limits, run_limited
from s2r.sources.urdf.xacro_sandbox import UnsafeXacro, sandbox

__all__ = ["PACKAGE_PATH_ENV", "XacroExpansion", "expand_xacro", "expand_xacro_files", "find_package", "is_xacro",
           "package_search_roots"]

PACKAGE_PATH_ENV = "ROS_PACKAGE_PATH"
_MAX_DEPTH = 3
_FIND_HINT = f"pass --package-path DIR with the folder that holds it, or add that folder to {PACKAGE_PATH_ENV}"


class PackageNotFound(LookupError):
    """A ``$(find pkg)`` package that no search folder holds."""

    def __init__(self, package: str) -> None:
        super().__init__(package)
        self.package = package


def is_xacro(path: Path) -> bool:
    """True for ``.xacro`` files (``robot.urdf.xacro``, ``robot.xacro``)."""
    return path.suffix == ".xacro"


def package_search_roots(package_paths: Sequence[Path] = ()) -> list[Path]:
    """The folders searched for ``$(find pkg)``: the given ones first, then ``ROS_PACKAGE_PATH``."""
    env = [Path(p) for p in os.environ.get(PACKAGE_PATH_ENV, "").split(os.pathsep) if p]
    return [Path(p) for p in package_paths] + env


def _package_name(folder: Path) -> str | None:
    manifest = folder / "package.xml"
    if not manifest.is_file():
        return None
    match = re.search(r"<name>\s*([^<\s]+)\s*</name>", manifest.read_text(encoding="utf-8", errors="replace"))
    return match.group(1) if match else None


def _walk(root: Path, depth: int) -> Iterator[Path]:
    yield root
    if depth <= 0:
        return
    try:
        children = sorted(p for p in root.iterdir() if p.is_dir() and not p.name.startswith("."))
    except OSError:
        return
    for child in children:
        yield from _walk(child, depth - 1)


def find_package(package: str, package_paths: Sequence[Path] = ()) -> Path:
    """The folder of ROS package ``package`` (what ``$(find package)`` expands to).

    Raises:
        PackageNotFound: no search folder holds it.
    """
    for root in package_search_roots(package_paths):
        if not root.is_dir():
            continue
        for folder in _walk(root, _MAX_DEPTH):
            name = _package_name(folder)
            if name == package or (name is None and folder.name == package and folder != root):
                return folder.resolve()
    raise PackageNotFound(package)


@contextmanager
def _find_resolver(package_paths: Sequence[Path]) -> Iterator[None]:
    from xacro import substitution_args

    def resolve(package: str) -> str:
        return str(find_package(package, package_paths))

    saved_func, saved_eval = substitution_args._eval_find, substitution_args._eval_dict["find"]
    substitution_args._eval_find = resolve
    substitution_args._eval_dict["find"] = resolve
    try:
        yield
    finally:
        substitution_args._eval_find = saved_func
        substitution_args._eval_dict["find"] = saved_eval


def _root_cause(exc: BaseException) -> BaseException:
    """The innermost exception under xacro's wrappers; an :class:`UnsafeXacro` refusal wins when present."""
    seen: set[int] = set()
    current: Any = exc
    while id(current) not in seen:
        seen.add(id(current))
        if isinstance(current, (UnsafeXacro, PackageNotFound)):
            return current  # type: ignore[no-any-return]
        inner = getattr(current, "exc", None) or current.__cause__ or current.__context__
        if not isinstance(inner, BaseException):
            return current  # type: ignore[no-any-return]
        current = inner
    return current  # type: ignore[no-any-return]


@dataclass(frozen=True)
class XacroExpansion:
    """A xacro expansion: the XML text, and the files ``<xacro:include>`` read with their text (path, text)."""

    text: str
    included: tuple[tuple[str, str], ...] = ()

    def macro_names(self, source_text: str = "") -> set[str]:
        """Names of the macros ``source_text`` (the top file) and every included file define."""
        texts = [source_text, *(text for _, text in self.included)]
        return {name for text in texts for name in re.findall(r"<xacro:macro\s+name\s*=\s*[\"']([^\"']+)[\"']", text)}


def expand_xacro(
    path: Path, *, xacro_args: Mapping[str, str] | None = None, package_paths: Sequence[Path] = (),
    limits: Limits | None = None, env: Mapping[str, str] | None = None,
) -> str:
    """Expand the xacro file ``path`` to URDF/SDF XML text: :func:`expand_xacro_files` without the included files."""
    return expand_xacro_files(path, xacro_args=xacro_args, package_paths=package_paths, limits=limits, env=env).text


def expand_xacro_files(
    path: Path, *, xacro_args: Mapping[str, str] | None = None, package_paths: Sequence[Path] = (),
    limits: Limits | None = None, env: Mapping[str, str] | None = None,
) -> XacroExpansion:
    """Expand the xacro file ``path`` to URDF/SDF XML text, in a child process under ``limits``.

    Args:
        path: the ``.xacro`` file.
        xacro_args: ``<xacro:arg>`` values, as ``name:=value`` on the xacro command line.
        package_paths: folders searched for ``$(find pkg)`` before ``ROS_PACKAGE_PATH``.
        limits: CPU, memory and wall-clock limits of the expansion (default :class:`Limits`).
        env: what ``$(env NAME)`` / ``$(optenv NAME default)`` see (``--env NAME=VALUE``); the machine's own
            environment is never read.

    Raises:
        SourceError: unresolved ``$(find)``, an undefined argument, a refused expression, a limit overrun,
            or any other xacro failure.
    """
    mappings = {str(k): str(v) for k, v in (xacro_args or {}).items()}
    paths = tuple(Path(p) for p in package_paths)
    values = {str(k): str(v) for k, v in (env or {}).items()}
    return run_limited(lambda: _expand_here(Path(path), mappings, paths, values), path=Path(path),
                       what="xacro expansion", limits=limits or Limits())


def _expand_here(path: Path, mappings: dict[str, str], package_paths: Sequence[Path],
                 env: Mapping[str, str] | None = None) -> XacroExpansion:
    """:func:`expand_xacro_files` in this process (the sandbox applies; no resource limits)."""
    import xacro

    included: list[str] = []
    try:
        with _find_resolver(package_paths), sandbox(Path(path), package_paths, env=env, included=included), \
                _quiet_xacro():
            doc = xacro.process_file(str(Path(path).resolve()), mappings=mappings)
    except Exception as exc:  # xacro raises XacroException, ExpatError, NameError, ...
        cause = _root_cause(exc)
        if isinstance(cause, MemoryError):
            raise MemoryError from None  # the isolation layer names the memory limit
        if isinstance(cause, RecursionError):
            raise SourceError("xacro expansion recursed too deeply (a macro that calls itself?)", path=path,
                              field="xacro", hint="fix the macro's recursion") from None
        if isinstance(cause, PackageNotFound):
            raise SourceError(f"package {cause.package!r} not found in any package folder", path=path,
                              field=f"$(find {cause.package})", hint=_FIND_HINT) from None
        if isinstance(cause, UnsafeXacro):
            raise SourceError(f"refused: {cause}", path=path, field="xacro",
                              hint="README 'Hostile input' lists what a xacro may do") from None
        raise SourceError(f"xacro expansion failed: {_safe_detail(exc, cause)}", path=path, field="xacro",
                          hint="fix the xacro file or pass the missing name:=value arguments") from None
    texts = _texts(included)
    _check_arguments(path, mappings, [t for _, t in _texts([str(Path(path).resolve())]) + texts])
    return XacroExpansion(str(doc.toprettyxml(indent="  ")), tuple(texts))


_DECLARED = re.compile(r"<xacro:arg\s+name\s*=\s*[\"']([^\"']+)[\"']")
_USED = re.compile(r"\$\(\s*arg\s+([^\s)]+)\s*\)")


def _check_arguments(path: Path, mappings: Mapping[str, str], texts: Sequence[str]) -> None:
    """SourceError for a ``name:=value`` argument no file declares (``<xacro:arg>``) or reads (``$(arg name)``):
    xacro ignores it silently, so a misspelt ``widht:=848`` would give a profile of the default width."""
    known = {name for text in texts for pattern in (_DECLARED, _USED) for name in pattern.findall(text)}
    unknown = sorted(name for name in mappings if name not in known and not name.startswith("_"))
    if not unknown:
        return
    import difflib

    name = unknown[0]
    close = difflib.get_close_matches(name, sorted(known), n=1, cutoff=0.6)
    declared = ", ".join(sorted(known)) or "none"
    raise SourceError(f"unknown xacro argument {name}:={mappings[name]}"
                      + (f" (did you mean {close[0]}?)" if close else "") + f"; the file declares: {declared}",
                      path=path, hint="spell it as declared: xacro ignores an argument it does not know, silently")


def _texts(paths: Sequence[str]) -> list[tuple[str, str]]:
    """(path, text) of each file once (xacro read them already: the sandbox allowed them)."""
    out: dict[str, str] = {}
    for name in paths:
        if name not in out:
            try:
                out[name] = read_regular_file(name, limit=MAX_TEXT_BYTES).decode("utf-8", errors="replace")
            except (OSError, ValueError):
                continue
    return list(out.items())


def _safe_detail(exc: BaseException, cause: BaseException) -> str:
    """A short description of a xacro failure that never quotes a loaded file's content.

    YAML errors carry a snippet of the offending line, so only their problem and line are kept; every other
    message is cut to its first line and 200 characters.
    """
    import yaml

    if isinstance(cause, yaml.YAMLError):
        mark = getattr(cause, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        return f"malformed YAML in a loaded file{where}: {getattr(cause, 'problem', None) or 'not valid YAML'}"
    lines = [line for line in str(exc).splitlines() if line.strip()]
    text = " ".join(lines[0].split()) if lines else ""
    if not text or text.startswith("<class"):
        text = f"{type(cause).__name__}: {' '.join(str(cause).split())}"
    return text[:200] or type(cause).__name__


@contextmanager
def _quiet_xacro() -> Iterator[None]:
    """Keep xacro's own stderr messages (warnings, ``xacro.message``) out of s2r's output: s2r reports the
    failure once, as its own one-line error."""
    import contextlib
    import io

    with contextlib.redirect_stderr(io.StringIO()), contextlib.redirect_stdout(io.StringIO()):
        yield
