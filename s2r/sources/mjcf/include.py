"""MJCF ``<include file=...>``: the included file's top-level children replace the element, confined to the scene's
folder, through the shared resolver (:mod:`s2r.sources.includes`).

MuJoCo (src/xml/xml.cc ``IncludeXML``) looks the file up relative to the main model's folder first, then relative
to the folder of the file holding the include; a file may be included at most once; an include has no children.
s2r reads only files inside the main scene's folder (:func:`s2r.sources.includes.resolve`: an absolute path, a
``..`` or a symbolic link that leads out of it is refused) within one :class:`~s2r.sources.includes.IncludeBudget`
(depth, files, bytes, elements).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from s2r.errors import SourceError
from s2r.sources.includes import IncludeBudget, IncludeNotAFile, MissingInclude, resolve
from s2r.sources.mjcf.pose import where
from s2r.sources.xmlparse import XmlDoc, parse_xml

__all__ = ["expand_includes"]


def _locate(doc: XmlDoc, name: str, current: Path, field: str, budget: IncludeBudget) -> Path:
    """MuJoCo's lookup: next to the main file, else next to the including file; both inside the scene's folder."""
    roots = [doc.path.parent]
    try:
        return resolve(name, including_file=doc.path, roots=roots, field=field, budget=budget, folders=False)
    except (MissingInclude, IncludeNotAFile):  # not a file next to the main file: next to the including one?
        if current == doc.path:
            raise
    return resolve(name, including_file=current, roots=roots, field=field, budget=budget, folders=False)


def _include(doc: XmlDoc, child: ET.Element, current: Path, seen: set[Path], budget: IncludeBudget) -> list[ET.Element]:
    if len(child):
        raise SourceError("an <include> element cannot have children", path=doc.path, field=where(doc, child))
    name = child.get("file")
    if name is None:
        raise SourceError("<include> has no file attribute", path=doc.path, field=where(doc, child),
                          hint="write <include file='part.xml'/>")
    field = where(doc, child, "file")
    path = _locate(doc, name, current, field, budget)
    if path in seen:
        raise SourceError(f"file {name!r} is already included (MuJoCo includes a file at most once)",
                          path=doc.path, field=field, hint="include it in one place only")
    seen.add(path)
    with budget.nested(path, including_file=doc.path, field=field):  # errors name the scene, ``field`` the file
        inner = parse_xml(budget.read(path, including_file=doc.path, field=field), path)
        budget.add_elements(len(inner.lines), including_file=doc.path, field=field)
        if not len(inner.root):
            raise SourceError(f"included file {name!r} holds no element under its root", path=doc.path,
                              field=where(doc, child))
        doc.lines.update(inner.lines)
        doc.files.update((id(element), path) for element in inner.root.iter())
        _expand(doc, inner.root, path, seen, budget)
    return list(inner.root)


def _expand(doc: XmlDoc, node: ET.Element, current: Path, seen: set[Path], budget: IncludeBudget) -> None:
    for index, child in reversed(list(enumerate(node))):
        if child.tag != "include":
            _expand(doc, child, current, seen, budget)
            continue
        elements = _include(doc, child, current, seen, budget)
        node.remove(child)
        for offset, element in enumerate(elements):
            node.insert(index + offset, element)


def expand_includes(doc: XmlDoc) -> list[Path]:
    """Replace every ``<include>`` of ``doc`` (an MJCF) by the children of the included file's root, recursively.

    Returns the files included (for the provenance). Raises SourceError naming the include element when the file
    is outside the scene's folder, missing, included twice, or the includes nest too deep or are too many."""
    budget = IncludeBudget()
    seen: set[Path] = {doc.path.resolve()}
    with budget.top(doc.path):
        _expand(doc, doc.root, doc.path, seen, budget)
    return budget.included
