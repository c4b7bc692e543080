"""MJCF ``<include file=...>``: the included file's top-level children replace the element, confined to the scene's
folder.

MuJoCo (src/xml/xml.cc ``IncludeXML``) looks the file up relative to the main model's folder first, then relative
to the folder of the file holding the include; a file may be included at most once; an include has no children.
s2r reads only files inside the main scene's folder: an absolute path, a ``..`` component or a symbolic link that
leads out of the folder is refused, as are includes nested more than :data:`MAX_DEPTH` deep or more than
:data:`MAX_INCLUDES` files in all. (One small resolver, to be replaced by the shared SDF/MJCF include resolver.)
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path, PurePosixPath

from s2r.errors import SourceError
from s2r.fileio import read_text_file
from s2r.sources.mjcf_pose import where
from s2r.sources.xmlparse import XmlDoc, parse_xml

__all__ = ["MAX_DEPTH", "MAX_INCLUDES", "expand_includes"]

MAX_DEPTH = 8
MAX_INCLUDES = 64


def _confined(doc: XmlDoc, include: ET.Element, name: str, folder: Path, here: Path) -> Path:
    """The included file: ``folder/name`` if it exists, else ``here/name``; refused when it leaves ``folder``."""
    field = where(doc, include, "file")
    parts = PurePosixPath(name.replace("\\", "/"))
    if not name.strip() or parts.is_absolute() or ".." in parts.parts or (len(name) > 1 and name[1] == ":"):
        raise SourceError(f"include file {name!r} is outside the scene's folder (absolute or with '..')",
                          path=doc.path, field=field, hint=f"copy the file into {folder} and include it by a "
                          "relative path")
    root = folder.resolve()
    for base in (folder, here):
        candidate = base / Path(*parts.parts)
        if not candidate.exists():
            continue
        real = candidate.resolve()
        if not real.is_relative_to(root):
            raise SourceError(f"include file {name!r} is a link leading outside the scene's folder ({real})",
                              path=doc.path, field=field, hint=f"copy the file into {folder}")
        return real
    raise SourceError(f"include file {name!r} not found next to the scene or the including file", path=doc.path,
                      field=field, hint="fix the file attribute (relative to the scene's folder)")


def _expand(doc: XmlDoc, node: ET.Element, folder: Path, here: Path, seen: set[Path], depth: int) -> None:
    for index, child in reversed(list(enumerate(node))):
        if child.tag != "include":
            _expand(doc, child, folder, here, seen, depth)
            continue
        if len(child):
            raise SourceError("an <include> element cannot have children", path=doc.path, field=where(doc, child))
        name = child.get("file")
        if name is None:
            raise SourceError("<include> has no file attribute", path=doc.path, field=where(doc, child),
                              hint="write <include file='part.xml'/>")
        path = _confined(doc, child, name, folder, here)
        if depth >= MAX_DEPTH:
            raise SourceError(f"includes nested more than {MAX_DEPTH} deep", path=doc.path, field=where(doc, child))
        if path in seen:
            raise SourceError(f"file {name!r} is already included (MuJoCo includes a file at most once)",
                              path=doc.path, field=where(doc, child), hint="include it in one place only")
        if len(seen) >= MAX_INCLUDES:
            raise SourceError(f"more than {MAX_INCLUDES} included files", path=doc.path, field=where(doc, child))
        seen.add(path)
        inner = parse_xml(read_text_file(path, error=SourceError), path)
        if not len(inner.root):
            raise SourceError(f"included file {name!r} holds no element under its root", path=doc.path,
                              field=where(doc, child))
        doc.lines.update(inner.lines)
        doc.files.update((id(element), path) for element in inner.root.iter())
        _expand(doc, inner.root, folder, path.parent, seen, depth + 1)
        node.remove(child)
        for offset, element in enumerate(list(inner.root)):
            node.insert(index + offset, element)


def expand_includes(doc: XmlDoc) -> int:
    """Replace every ``<include>`` of ``doc`` (an MJCF) by the children of the included file's root, recursively.

    Returns the number of files included. Raises SourceError naming the include element when the file is outside
    the scene's folder, missing, included twice, or the includes nest too deep or are too many."""
    folder = doc.path.parent
    seen: set[Path] = {doc.path.resolve()}
    _expand(doc, doc.root, folder, folder, seen, 0)
    return len(seen) - 1
