"""Parsing untrusted text safely: YAML with a strict loader (no object tags, no duplicate keys, no alias bombs, a
node budget counted while parsing) and XML without a DOCTYPE.
Kept apart from :mod:`s2r.fileio` so that reading and writing files does not load
PyYAML (13 ms of every command's start-up)."""

from __future__ import annotations

from pathlib import Path
from typing import Any
from xml.parsers import expat

import yaml
from yaml.composer import Composer
from yaml.constructor import SafeConstructor
from yaml.resolver import Resolver

from s2r.errors import S2RError

__all__ = ["MAX_YAML_COMPOSED", "MAX_YAML_NODES", "StrictSafeLoader", "check_yaml_graph", "parse_yaml",
           "run_xml_parser", "safe_xml_parser"]


#: Most nodes a YAML document may expand to, every alias counted as a copy of its anchor's nodes (the largest
#: calibration files s2r reads hold a few thousand numbers).
MAX_YAML_NODES = 1_000_000
#: Most nodes a YAML document may hold as written (counted while parsing, before anything is built): a fleet of
#: 10000 robots holds about 160000. Parsing stops at the first node past it, after about 1 s of CPU (libyaml's
#: parser, s2r's counting composer: ~4 us a node) and ~100 MB; a 2 MB list of a million numbers took 105 s and
#: 840 MB to be refused after it was built.
MAX_YAML_COMPOSED = 250_000


def _fast_base() -> type:
    """libyaml's C parser under PyYAML's (Python) composer, safe constructor and resolver: 5x faster than the
    pure-Python parser, and the composer stays ours (the node count). The pure-Python SafeLoader without
    libyaml."""
    try:
        from yaml.cyaml import CParser  # type: ignore[attr-defined]
    except ImportError:
        return yaml.SafeLoader

    class _CSafeComposingLoader(Composer, CParser, SafeConstructor, Resolver):  # type: ignore[misc]
        def __init__(self, stream: str) -> None:
            CParser.__init__(self, stream)
            Composer.__init__(self)
            SafeConstructor.__init__(self)
            Resolver.__init__(self)

    return _CSafeComposingLoader


_BaseLoader: Any = _fast_base()


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    if isinstance(node, yaml.MappingNode):
        return [n for pair in node.value for n in pair]
    return []


def check_yaml_graph(root: yaml.Node, *, limit: int = MAX_YAML_NODES) -> None:
    """Refuse a composed YAML graph that contains itself (``&r [1.0, *r]``) or that expands to more than
    ``limit`` nodes through aliases (a "billion laughs" bomb: 9 levels of 10 aliases in 2.6 kB is 10^9).

    Walks the graph once (shared nodes are sized once), without recursion.

    Raises:
        yaml.composer.ComposerError: naming the line of the offending node.
    """
    sizes: dict[int, int] = {}
    entered: set[int] = set()
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, leaving = stack.pop()
        key = id(node)
        if leaving:
            sizes[key] = 1 + sum(sizes[id(child)] for child in _children(node))
            if sizes[key] > limit:
                raise yaml.composer.ComposerError(
                    None, None, f"aliases expand to more than {limit} nodes (an alias bomb?)", node.start_mark)
            continue
        if key in sizes:
            continue
        if key in entered:
            raise yaml.composer.ComposerError(None, None, "recursive alias: a node that contains itself",
                                              node.start_mark)
        entered.add(key)
        stack.append((node, True))
        stack.extend((child, False) for child in _children(node))


class StrictSafeLoader(_BaseLoader):  # type: ignore[misc]
    """PyYAML's safe loader, stricter: a document of more than :data:`MAX_YAML_COMPOSED` nodes is refused while
    it is parsed (at the first node past the bound), a key repeated in one mapping is an error (naming the key and
    its line, instead of the last one silently winning), the object-building tags ``!!binary !!set !!omap !!pairs
    !!python/...`` are refused (only maps, lists, strings, numbers, booleans, null and dates are built), and a
    document whose aliases recurse or expand past :data:`MAX_YAML_NODES` nodes is refused before it is built
    (:func:`check_yaml_graph`)."""

    _composed = 0

    def compose_node(self, parent: yaml.Node | None, index: Any) -> yaml.Node:
        """The next node, counted; ComposerError past :data:`MAX_YAML_COMPOSED`."""
        self._composed += 1
        if self._composed > MAX_YAML_COMPOSED:
            raise yaml.composer.ComposerError(
                None, None, f"more than {MAX_YAML_COMPOSED} values (no s2r file holds that many: is it the right "
                "file?)", self.peek_event().start_mark)
        return super().compose_node(parent, index)  # type: ignore[no-any-return]

    def compose_document(self) -> yaml.Node | None:
        """The document's node graph, checked by :func:`check_yaml_graph`."""
        node: yaml.Node | None = super().compose_document()
        if node is not None:
            check_yaml_graph(node)
        return node

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        """The mapping of ``node``; ConstructorError on a duplicate key."""
        seen: set[Any] = set()
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge" or not isinstance(key_node, yaml.ScalarNode):
                continue
            key = self.construct_object(key_node, deep=True)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r} (each key may appear once)", key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep=deep)  # type: ignore[no-any-return]

    def refuse_tag(self, node: yaml.Node) -> Any:
        """Constructor for tags that build objects: always an error."""
        raise yaml.constructor.ConstructorError(None, None, f"tag {node.tag!r} is not allowed", node.start_mark)


for _tag in ("binary", "set", "omap", "pairs"):
    StrictSafeLoader.add_constructor(f"tag:yaml.org,2002:{_tag}", StrictSafeLoader.refuse_tag)


def parse_yaml(text: str, *, path: str | Path | None = None, error: type[S2RError] = S2RError,
               loader: type[StrictSafeLoader] = StrictSafeLoader) -> Any:
    """Parse YAML text with :class:`StrictSafeLoader` (or a subclass); ``error`` naming the file and line when
    it is malformed, repeats a key or uses a refused tag."""
    try:
        return yaml.load(text, Loader=loader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}" if mark is not None else None
        problem = getattr(exc, "problem", None) or "not valid YAML"
        raise error(f"malformed YAML: {problem}", path=path, field=where) from None
    except (ValueError, TypeError, AttributeError, OverflowError, RecursionError) as exc:
        # the safe loader's int/float/timestamp constructors raise plain errors on odd scalars (2026-13-45)
        raise error(f"malformed YAML: {exc}", path=path) from None


class _RefusedXml(Exception):
    """Raised from inside expat when a document declares a DOCTYPE or entities."""


def _refuse_doctype(*_: Any) -> None:
    raise _RefusedXml("DOCTYPE")


def safe_xml_parser() -> Any:
    """An expat parser that refuses any ``<!DOCTYPE>`` (so no DTD, no entity declarations, no entity
    amplification, no external entities). Parse with :func:`run_xml_parser` to get one-line errors."""
    parser = expat.ParserCreate()
    parser.StartDoctypeDeclHandler = _refuse_doctype
    parser.EntityDeclHandler = _refuse_doctype
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    return parser


def run_xml_parser(parser: Any, text: str, *, path: str | Path, error: type[S2RError] = S2RError) -> None:
    """Feed ``text`` to a :func:`safe_xml_parser`; ``error`` (one line, file and line) when it is refused or
    malformed."""
    try:
        parser.Parse(text, True)
    except _RefusedXml:
        raise error("XML with a <!DOCTYPE> (DTD or entity declarations) is refused", path=path,
                    field=f"line {parser.CurrentLineNumber}",
                    hint="remove the <!DOCTYPE ...> block; these files never need one") from None
    except expat.ExpatError as exc:
        raise error(f"malformed XML: {expat.ErrorString(exc.code)} at column {exc.offset + 1}", path=path,
                    field=f"line {exc.lineno}", hint="fix the XML syntax there (unclosed or mismatched tag?)") from None
