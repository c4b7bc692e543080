"""SDF ``<include>`` of ``model://NAME`` (and file) URIs, resolved the way Gazebo does, before the SDF is read.

A ``model://NAME`` URI names a model folder ``NAME`` found in, in order: the ``--package-path`` folders,
``GZ_SIM_RESOURCE_PATH`` (gz-sim), ``IGN_GAZEBO_RESOURCE_PATH`` (older gz-sim) and ``GAZEBO_MODEL_PATH``
(Gazebo classic), each a ``:``-separated list. The folder's ``model.config`` names the SDF file
(``<sdf>model.sdf</sdf>``; default ``model.sdf``). The included ``<model>`` replaces the ``<include>``, renamed
by the include's ``<name>`` and placed by its ``<pose>`` (which wins over the model's own). Fuel (https) URIs
are not fetched: the error names the URI and what to do.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

from s2r.errors import SourceError
from s2r.fileio import read_text_file
from s2r.sources.xmlparse import XmlDoc, parse_xml

__all__ = ["MODEL_PATH_ENVS", "model_search_roots", "resolve_includes"]

MODEL_PATH_ENVS = ("GZ_SIM_RESOURCE_PATH", "IGN_GAZEBO_RESOURCE_PATH", "GAZEBO_MODEL_PATH")
_MAX_DEPTH = 8


def model_search_roots(package_paths: Sequence[Path] = ()) -> list[Path]:
    """Folders searched for ``model://NAME``: ``package_paths`` first, then the environment variables."""
    roots = [Path(p) for p in package_paths]
    for env in MODEL_PATH_ENVS:
        roots += [Path(p) for p in os.environ.get(env, "").split(os.pathsep) if p]
    return roots


def _model_file(folder: Path) -> Path:
    config = folder / "model.config"
    if config.is_file():
        try:
            root = ET.fromstring(read_text_file(config, error=SourceError))
        except ET.ParseError:
            root = None
        names = [] if root is None else [(n.text or "").strip() for n in root.iter("sdf")]
        for name in names:
            if name and (folder / name).is_file():
                return folder / name
    return folder / "model.sdf"


def _locate(uri: str, base: Path, package_paths: Sequence[Path], doc: XmlDoc, line: int | None) -> Path:
    where = f"<include> line {line}" if line else "<include>"
    if uri.startswith(("http://", "https://")):
        raise SourceError(f"cannot include {uri}: Fuel models are not downloaded", path=doc.path, field=where,
                          hint="download the model and pass its parent folder with --package-path")
    if uri.startswith("model://"):
        name = uri[len("model://"):].strip("/")
        head, _, rest = name.partition("/")
        for root in model_search_roots(package_paths):
            if (root / head).is_dir():
                folder = root / head / rest if rest else root / head
                return folder if folder.is_file() else _model_file(folder)
        listed = ", ".join(MODEL_PATH_ENVS)
        raise SourceError(f"model {head!r} ({uri}) not found in any model folder", path=doc.path, field=where,
                          hint=f"pass --package-path DIR with the folder holding {head}/, or set one of {listed}")
    path = Path(uri.removeprefix("file://"))
    path = path if path.is_absolute() else base / path
    if path.is_dir():
        return _model_file(path)
    if not path.is_file():
        raise SourceError(f"included file {uri!r} not found", path=doc.path, field=where,
                          hint="fix the <uri> or pass --package-path with the model folder")
    return path


def _included_model(path: Path, include: ET.Element, doc: XmlDoc, line: int | None) -> ET.Element:
    inner = parse_xml(read_text_file(path, error=SourceError), path)
    model = inner.root if inner.root.tag == "model" else inner.root.find("model")
    if model is None:
        raise SourceError(f"included file {path} holds no <model>", path=doc.path,
                          field=f"<include> line {line}" if line else "<include>")
    doc.lines.update(inner.lines)
    resolve_includes(inner, path.parent, (), _depth=1)
    doc.lines.update(inner.lines)
    name, pose = include.findtext("name"), include.find("pose")
    if name and name.strip():
        model.set("name", name.strip())
    if pose is not None:
        for old in model.findall("pose"):
            model.remove(old)
        model.insert(0, pose)
    return model


def resolve_includes(doc: XmlDoc, base: Path, package_paths: Sequence[Path] = (), *, _depth: int = 0) -> None:
    """Replace every ``<include>`` of ``doc`` (an SDF) by the ``<model>`` it names, recursively; SourceError naming
    the include's line when a URI cannot be resolved."""
    if _depth > _MAX_DEPTH:
        raise SourceError("includes nested too deeply (a model including itself?)", path=doc.path, field="<include>")
    parents = [p for p in doc.root.iter() if p.find("include") is not None]
    for parent in parents:
        for index, include in enumerate(list(parent)):
            if include.tag != "include":
                continue
            line = doc.line(include)
            uri = (include.findtext("uri") or "").strip()
            if not uri:
                raise SourceError("<include> has no <uri>", path=doc.path, field=f"<include> line {line}")
            path = _locate(uri, base, package_paths, doc, line)
            model = _included_model(path, include, doc, line)
            resolve_includes(XmlDoc(model, path, doc.lines), path.parent, package_paths, _depth=_depth + 1)
            parent.remove(include)
            parent.insert(index, model)
