"""MJCF ``<default>`` classes: the attribute values an element takes when it does not write them.

The top-level ``<default>`` is class ``main`` (unless it names itself); a nested ``<default class=...>``
inherits every attribute of its parent and overrides some. An element uses its own ``class``, else the
``childclass`` of the nearest enclosing body or frame, else ``main``. A class that sets one orientation form
(``quat``, ``axisangle``, ``xyaxes``, ``zaxis``, ``euler``) replaces the orientation it inherited, and an element's
own orientation wins over its class's (checked against MuJoCo in tests).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

from s2r.errors import SourceError
from s2r.sources.mjcf.pose import ORIENTATIONS, where
from s2r.sources.xmlparse import XmlDoc

__all__ = ["Defaults", "read_defaults"]

#: Attributes a defaults class never provides (MuJoCo's ``nodefault`` rows).
_NOT_DEFAULTED = frozenset({"name", "class", "target", "childclass"})
_MAX_CLASSES = 10_000


def _merge(base: dict[str, str], own: dict[str, str]) -> dict[str, str]:
    """``base`` overridden by ``own``; an orientation in ``own`` drops every orientation of ``base``."""
    kept = {k: v for k, v in base.items() if not (k in ORIENTATIONS and any(o in own for o in ORIENTATIONS))}
    kept.update({k: v for k, v in own.items() if k not in _NOT_DEFAULTED})
    return kept


@dataclass
class Defaults:
    """Every class's attributes per element tag (``classes[name][tag]``)."""

    classes: dict[str, dict[str, dict[str, str]]] = field(default_factory=lambda: {"main": {}})

    def _check(self, doc: XmlDoc, element: ET.Element, name: str, attribute: str) -> str:
        if name not in self.classes:
            known = ", ".join(sorted(self.classes)[:20])
            raise SourceError(f"unknown default class {name!r} (classes: {known})", path=doc.path,
                              field=where(doc, element, attribute), hint="name a <default class=...> of the model")
        return name

    def childclass(self, doc: XmlDoc, element: ET.Element, active: str) -> str:
        """The class active inside ``element`` (a body, frame or worldbody)."""
        name = element.get("childclass")
        return active if name is None else self._check(doc, element, name, "childclass")

    def class_attrs(self, doc: XmlDoc, element: ET.Element, tag: str, active: str) -> dict[str, str]:
        """The attributes ``element``'s class gives a ``<tag>`` element."""
        name = element.get("class")
        name = active if name is None else self._check(doc, element, name, "class")
        return dict(self.classes[name].get(tag, {}))

    def attrs(self, doc: XmlDoc, element: ET.Element, tag: str, active: str) -> dict[str, str]:
        """``element``'s attributes over its class's (an own orientation replaces the class's)."""
        return _merge(self.class_attrs(doc, element, tag, active), dict(element.attrib)) | {
            k: v for k, v in element.attrib.items() if k in ("name", "target")}

    def camera_pose(self, doc: XmlDoc, element: ET.Element, active: str) -> dict[str, str]:
        """The class attributes a camera's pose falls back on (``pos`` and one orientation)."""
        return self.class_attrs(doc, element, "camera", active)


def _read(doc: XmlDoc, node: ET.Element, name: str, parent: dict[str, dict[str, str]], out: Defaults) -> None:
    if name in out.classes and name != "main":
        raise SourceError(f"default class {name!r} is defined twice", path=doc.path, field=where(doc, node, "class"),
                          hint="give each <default> a unique class name")
    if len(out.classes) > _MAX_CLASSES:
        raise SourceError(f"more than {_MAX_CLASSES} default classes", path=doc.path, field=where(doc, node))
    own = {tag: dict(attrs) for tag, attrs in (out.classes.get(name) or parent).items()}
    for child in node:
        if child.tag == "default":
            continue
        given = [k for k in ORIENTATIONS if k in child.attrib]
        if len(given) > 1:
            raise SourceError(f"multiple orientation attributes ({', '.join(given)})", path=doc.path,
                              field=where(doc, child), hint="keep one of quat, axisangle, xyaxes, zaxis, euler")
        own[child.tag] = _merge(own.get(child.tag, {}), dict(child.attrib))
    out.classes[name] = own
    for child in node.findall("default"):
        inner = child.get("class")
        if not inner:
            raise SourceError("a nested <default> needs a class name", path=doc.path, field=where(doc, child),
                              hint="write <default class='NAME'>")
        _read(doc, child, inner, own, out)


def read_defaults(doc: XmlDoc) -> Defaults:
    """All ``<default>`` classes of the model (after includes are expanded)."""
    out = Defaults()
    for node in doc.root.findall("default"):
        name = node.get("class", "main")
        _read(doc, node, name, {}, out)
        out.classes["main"] = out.classes[name]  # a top-level class under another name is still the model's default
    return out
