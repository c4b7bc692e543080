"""XML parsing with line numbers (standard library expat + ElementTree elements).

Line numbers are kept per element so lint findings can say ``file:line``; malformed XML becomes one
:class:`~s2r.errors.SourceError` naming the file, the line and what to fix.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

from s2r.errors import SourceError
from s2r.safeparse import run_xml_parser, safe_xml_parser

__all__ = ["XmlDoc", "parse_xml"]


@dataclass
class XmlDoc:
    """A parsed XML document: its root element and the 1-based source line of each element."""

    root: ET.Element
    path: Path
    lines: dict[int, int] = field(default_factory=dict)
    #: The file an element was read from when it is not ``path`` (elements pulled in by an include).
    files: dict[int, Path] = field(default_factory=dict)

    def line(self, element: ET.Element | None) -> int | None:
        """Source line (1-based) where ``element`` starts, or None when unknown."""
        return None if element is None else self.lines.get(id(element))


def parse_xml(text: str, path: Path) -> XmlDoc:
    """Parse XML ``text`` (read from ``path``, used in messages) into an :class:`XmlDoc`.

    Raises:
        SourceError: malformed XML, naming the file and the line.
    """
    builder = ET.TreeBuilder()
    lines: dict[int, int] = {}
    parser = safe_xml_parser()  # refuses <!DOCTYPE>: no entity expansion from a stranger's file

    def start(tag: str, attrs: dict[str, str]) -> None:
        element = builder.start(tag, attrs)
        lines[id(element)] = parser.CurrentLineNumber

    parser.StartElementHandler = start
    parser.EndElementHandler = builder.end
    parser.CharacterDataHandler = builder.data
    run_xml_parser(parser, text, path=path, error=SourceError)
    root = builder.close()
    return XmlDoc(root=root, path=path, lines=lines)
