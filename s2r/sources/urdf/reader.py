"""URDF (after xacro expansion) to a :class:`Description`: links, joints, ``<gazebo reference>`` cameras."""

from __future__ import annotations

import xml.etree.ElementTree as ET

from s2r.errors import SourceError
from s2r.sources.description import CameraSpec, Description, JointSpec
from s2r.sources.sensors import camera_specs, parse_origin
from s2r.sources.xmlparse import XmlDoc

__all__ = ["parse_urdf"]


def _link_ref(doc: XmlDoc, joint: ET.Element, role: str, links: dict[str, int | None]) -> str:
    node = joint.find(role)
    name = joint.get("name", "?")
    where = f"<joint name={name!r}> line {doc.line(joint)}"
    if node is None or not node.get("link"):
        raise SourceError(f"has no <{role} link=...>", path=doc.path, field=where, hint=f"add <{role} link='...'/>")
    link = node.get("link", "")
    if link not in links:
        raise SourceError(f"{role} link {link!r} is not declared by any <link>", path=doc.path, field=where,
                          hint=f"add <link name={link!r}/> or fix the joint's {role}")
    return link


def _joints(doc: XmlDoc, links: dict[str, int | None]) -> list[JointSpec]:
    joints = []
    for node in doc.root.findall("joint"):
        joints.append(JointSpec(
            name=node.get("name", ""), type=node.get("type", "fixed"),
            parent=_link_ref(doc, node, "parent", links), child=_link_ref(doc, node, "child", links),
            T_parent_child=parse_origin(doc, node.find("origin")), line=doc.line(node),
        ))
    return joints


def _cameras(doc: XmlDoc, links: dict[str, int | None]) -> list[CameraSpec]:
    cameras: list[CameraSpec] = []
    for gazebo in doc.root.findall("gazebo"):
        sensors = gazebo.findall("sensor")
        if not sensors:
            continue
        link = gazebo.get("reference")
        if not link:
            raise SourceError("a <gazebo> block with a <sensor> needs reference='LINK'", path=doc.path,
                              field=f"<gazebo> line {doc.line(gazebo)}", hint="name the link the sensor is on")
        if link not in links:
            raise SourceError(f"reference {link!r} is not declared by any <link>", path=doc.path,
                              field=f"<gazebo reference={link!r}> line {doc.line(gazebo)}",
                              hint=f"add <link name={link!r}/> or fix the reference")
        for sensor in sensors:
            cameras.extend(camera_specs(doc, sensor, link))
    return cameras


def parse_urdf(doc: XmlDoc) -> Description:
    """Links, joints (``T_parent_child`` from ``<origin>``) and camera sensors of a ``<robot>`` document."""
    if doc.root.tag != "robot":
        raise SourceError(f"expected a <robot> root element, got <{doc.root.tag}>", path=doc.path,
                          field=f"<{doc.root.tag}>", hint="is this a URDF file?")
    links: dict[str, int | None] = {}
    for node in doc.root.findall("link"):
        name = node.get("name")
        if not name:
            raise SourceError("a <link> has no name", path=doc.path, field=f"<link> line {doc.line(node)}",
                              hint="add name='...'")
        links[name] = doc.line(node)
    return Description(path=doc.path, kind="urdf", links=links, joints=_joints(doc, links),
                       cameras=_cameras(doc, links))
