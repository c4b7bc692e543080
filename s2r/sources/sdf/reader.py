"""SDF (``<sdf>`` with models, or a ``<world>``) to a :class:`Description`.

Link poses are relative to their model (SDF's default ``relative_to``; a ``relative_to`` naming another
link of the same model is followed); nested models compose their poses and scope names ``outer::inner``.
Each link becomes a fixed pseudo-joint from its model's frame, so the kinematics are the same as URDF's.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

from s2r.errors import SourceError
from s2r.sources.description import CameraSpec, Description, FloatArray, JointSpec
from s2r.sources.sensors import camera_specs, parse_pose
from s2r.sources.xmlparse import XmlDoc

__all__ = ["MAX_MODEL_NESTING", "parse_sdf"]

#: Nested ``<model>`` levels read (real worlds nest a handful; the limit keeps recursion far from Python's).
MAX_MODEL_NESTING = 64


class _Collector:
    def __init__(self, doc: XmlDoc) -> None:
        self.doc = doc
        self.links: dict[str, int | None] = {}
        self.joints: list[JointSpec] = []
        self.cameras: list[CameraSpec] = []
        self.sdf_joints: list[tuple[str, ET.Element]] = []

    def model(self, node: ET.Element, frame: str, T_frame_model: FloatArray, prefix: str, depth: int = 0) -> None:
        if depth > MAX_MODEL_NESTING:
            raise SourceError(f"models nested more than {MAX_MODEL_NESTING} deep", path=self.doc.path,
                              field=f"<model> line {self.doc.line(node)}", hint="flatten the nested <model> elements")
        name = prefix + node.get("name", "model")
        model_frame = f"{name}::__model__"
        self.links[model_frame] = self.doc.line(node)
        self.joints.append(JointSpec(name=f"<model {name}>", type="fixed", parent=frame, child=model_frame,
                                     T_parent_child=T_frame_model, line=self.doc.line(node)))
        local = {link.get("name", ""): link for link in node.findall("link")}
        for link in node.findall("link"):
            self.link(link, model_frame, f"{name}::", local)
        for joint in node.findall("joint"):
            self.sdf_joints.append((f"{name}::", joint))
        for inner in node.findall("model"):
            self.model(inner, model_frame, parse_pose(self.doc, inner.find("pose")), f"{name}::", depth + 1)

    def link(self, node: ET.Element, model_frame: str, prefix: str, local: dict[str, ET.Element]) -> None:
        name = prefix + node.get("name", "")
        pose = node.find("pose")
        parent = model_frame
        relative_to = None if pose is None else pose.get("relative_to")
        if relative_to and relative_to != "__model__":
            if relative_to not in local:
                raise SourceError(f"pose relative_to {relative_to!r} names no link of this model", path=self.doc.path,
                                  field=f"<link name={name!r}> line {self.doc.line(node)}",
                                  hint="name a link of the same model")
            parent = prefix + relative_to
        self.links[name] = self.doc.line(node)
        self.joints.append(JointSpec(name=f"<link {name} pose>", type="fixed", parent=parent, child=name,
                                     T_parent_child=parse_pose(self.doc, pose), line=self.doc.line(node)))
        for sensor in node.findall("sensor"):
            self.cameras.extend(camera_specs(self.doc, sensor, name))

    def check_joints(self) -> None:
        for prefix, joint in self.sdf_joints:
            for role in ("parent", "child"):
                ref = (joint.findtext(role) or "").strip()
                if ref == "world" or prefix + ref in self.links or ref in self.links:
                    continue
                raise SourceError(f"{role} link {ref!r} is not declared by any <link>", path=self.doc.path,
                                  field=f"<joint name={joint.get('name', '?')!r}> line {self.doc.line(joint)}",
                                  hint=f"add <link name={ref!r}> or fix the joint's <{role}>")


def parse_sdf(doc: XmlDoc) -> Description:
    """Links (as fixed pseudo-joints from their model frame), joints checked, and camera sensors of an SDF."""
    root = doc.root
    if root.tag not in ("sdf", "model", "world"):
        raise SourceError(f"expected an <sdf> root element, got <{root.tag}>", path=doc.path, field=f"<{root.tag}>",
                          hint="is this an SDF file?")
    collector = _Collector(doc)
    collector.links["world"] = doc.line(root)
    containers = [root, *root.findall("world")] if root.tag == "sdf" else [root]
    models = [m for c in containers for m in c.findall("model")] if root.tag != "model" else [root]
    for model in models:
        collector.model(model, "world", parse_pose(doc, model.find("pose")), "")
    collector.check_joints()
    return Description(path=doc.path, kind="sdf", links=collector.links, joints=collector.joints,
                       cameras=collector.cameras)

