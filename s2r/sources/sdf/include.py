"""SDF ``<include>`` of ``model://NAME`` (and file) URIs, expanded the way Gazebo does, before the SDF is read.

A ``model://NAME`` URI names a model folder ``NAME`` found in, in order: the ``--package-path`` folders,
``GZ_SIM_RESOURCE_PATH`` (gz-sim), ``IGN_GAZEBO_RESOURCE_PATH`` (older gz-sim) and ``GAZEBO_MODEL_PATH``
(Gazebo classic), each a ``:``-separated list, then the description's own folder and its ROS package (the nearest
folder up to 3 levels above holding a ``package.xml``, as for xacro). The folder's ``model.config``
names the SDF file (``<sdf>model.sdf</sdf>``; default ``model.sdf``). The included ``<model>`` replaces the
``<include>``, renamed by the include's ``<name>`` and placed by its ``<pose>`` (which wins over the model's own).

Where a URI may point and how much may be included is :mod:`s2r.sources.includes` (confined to those folders; a
depth, file, byte and element budget over the whole expansion). The expansion runs in a child process under CPU,
memory and wall-clock limits as xacro does (:mod:`s2r.sources.isolation`; :data:`INCLUDE_LIMITS`, tighter).
Includes that name nothing here (an unknown model, a web/Fuel URI) are left out and returned as
:class:`~s2r.sources.description.SkippedInclude`: the caller decides whether the cameras asked for could be in them
(:func:`s2r.sources.loader.stereo_pair`).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from s2r.errors import SourceError
from s2r.sources.description import SkippedInclude
from s2r.sources.includes import IncludeBudget, MissingInclude, is_cameraless, resolve
from s2r.sources.isolation import Limits, run_limited
from s2r.sources.urdf.xacro_sandbox import allowed_roots
from s2r.sources.xmlparse import XmlDoc, parse_xml

__all__ = ["INCLUDE_LIMITS", "MODEL_PATH_ENVS", "expand_includes", "model_search_roots"]

MODEL_PATH_ENVS = ("GZ_SIM_RESOURCE_PATH", "IGN_GAZEBO_RESOURCE_PATH", "GAZEBO_MODEL_PATH")
#: Resource limits of an SDF include expansion (the budget of :class:`IncludeBudget` stops it long before).
INCLUDE_LIMITS = Limits(cpu_s=5, memory_bytes=1 << 30, wall_s=8.0)
_LIMIT_HINT = "includes that fan out or nest without end; fix the file"
#: What an included file may hold instead of a ``<model>`` (Gazebo's own ``sun`` is a ``<light>``): no camera there.
_NO_CAMERA_TAGS = ("light", "actor")


@dataclass(frozen=True)
class _Result:
    """What the child returns: the expanded tree as XML bytes (pickling an Element tree is ~50x slower than
    serialising it) and each element's line, in document order."""

    xml: bytes
    lines: list[int | None]
    included: list[Path]
    skipped: list[SkippedInclude]


def model_search_roots(package_paths: Sequence[Path] = ()) -> list[Path]:
    """Folders searched for ``model://NAME``: ``package_paths`` first, then the environment variables."""
    roots = [Path(p) for p in package_paths]
    for env in MODEL_PATH_ENVS:
        roots += [Path(p) for p in os.environ.get(env, "").split(os.pathsep) if p]
    return roots


class _Expander:
    def __init__(self, doc: XmlDoc, roots: Sequence[Path], budget: IncludeBudget) -> None:
        self.lines = dict(doc.lines)
        self.roots, self.budget = list(roots), budget
        self.skipped: list[SkippedInclude] = []

    def expand(self, element: ET.Element, file: Path) -> None:
        """Replace every ``<include>`` below ``element`` (read from ``file``) by its model, recursively."""
        parents = [p for p in element.iter() if any(c.tag == "include" for c in p)]
        for parent in parents:
            children: list[ET.Element] = []
            for child in parent:
                model = self.include(child, file) if child.tag == "include" else child
                if model is not None:
                    children.append(model)
            parent[:] = children

    def include(self, include: ET.Element, file: Path) -> ET.Element | None:
        line = self.lines.get(id(include))
        field = f"<include> line {line}" if line else "<include>"
        uri = (include.findtext("uri") or "").strip()
        if not uri:
            raise SourceError("<include> has no <uri>", path=file, field=field, hint="add <uri>model://NAME</uri>")
        try:
            path = resolve(uri, including_file=file, roots=self.roots, field=field, budget=self.budget)
        except MissingInclude as exc:
            self.skipped.append(SkippedInclude(uri=uri, message=exc.message, path=str(file), field=field,
                                               hint=exc.hint or "", cameraless=is_cameraless(uri)))
            return None
        with self.budget.nested(path, including_file=file, field=field):
            inner = parse_xml(self.budget.read(path, including_file=file, field=field), path)
            self.budget.add_elements(len(inner.lines), including_file=file, field=field)
            self.lines.update(inner.lines)
            model = inner.root if inner.root.tag == "model" else inner.root.find("model")
            if model is None and (inner.root.tag in _NO_CAMERA_TAGS or any(
                    inner.root.find(tag) is not None for tag in _NO_CAMERA_TAGS)):
                return None  # model://sun is a <light>: nothing a camera could be on
            if model is None:
                raise SourceError(f"included file {path.name!r} holds no <model>", path=file, field=field,
                                  hint="include a model's SDF")
            self.expand(model, path)
        name, pose = include.findtext("name"), include.find("pose")
        if name and name.strip():
            model.set("name", name.strip())
        if pose is not None:
            for old in model.findall("pose"):
                model.remove(old)
            model.insert(0, pose)
        return model


def _expand(doc: XmlDoc, roots: Sequence[Path], budget: IncludeBudget) -> _Result:
    expander = _Expander(doc, roots, budget)
    with budget.top(doc.path):
        expander.expand(doc.root, doc.path)
    lines = [expander.lines.get(id(e)) for e in doc.root.iter()]
    return _Result(ET.tostring(doc.root), lines, list(budget.included), expander.skipped)


def expand_includes(doc: XmlDoc, package_paths: Sequence[Path] = (), *,
                    budget: IncludeBudget | None = None) -> tuple[list[Path], list[SkippedInclude]]:
    """Replace every ``<include>`` of ``doc`` (an SDF, modified in place) by the ``<model>`` it names.

    Returns:
        (the files read, in order; the includes left out because they name nothing here).

    Raises:
        SourceError: an include without a URI, outside the allowed folders, including itself, over the budget,
            over the resource limits, or naming a file without a ``<model>``.
    """
    if not any(e.tag == "include" for e in doc.root.iter()):
        return [], []
    roots = [*model_search_roots(package_paths), *allowed_roots(doc.path, ())]  # + its folder and ROS package
    spent = budget or IncludeBudget()
    result = run_limited(lambda: _expand(doc, roots, spent), path=doc.path, what="SDF include expansion",
                         limits=INCLUDE_LIMITS, field="<include>", hint=_LIMIT_HINT)
    doc.root = ET.fromstring(result.xml)  # s2r's own serialisation of an already checked tree: no DOCTYPE possible
    doc.lines = {id(e): line for e, line in zip(doc.root.iter(), result.lines, strict=True) if line is not None}
    return result.included, result.skipped
