"""MJCF ``<keyframe><key>``: the body poses at a keyframe's joint positions, as MuJoCo's ``mj_kinematics`` places them.

``qpos`` holds, body by body in the model's order (depth first, as written) and joint by joint: a free joint's
position and quaternion (7 numbers, the body's pose in the world), a ball joint's quaternion (4), a hinge's angle or
a slide's displacement (1, radians or metres whatever ``<compiler angle>``). A body's pose is its written pose
followed by each joint's motion in turn: a hinge turns by ``qpos - ref`` about its axis through its ``pos``, a slide
moves ``qpos - ref`` along its axis, a ball turns by its quaternion about its ``pos``. ``mpos`` / ``mquat`` place
the mocap bodies (in the world). A key without ``qpos`` keeps the initial state (qpos0: the model as written).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import numpy as np

from s2r.errors import SourceError
from s2r.geometry import make_transform
from s2r.sources.description import FloatArray
from s2r.sources.mjcf.pose import Compiler, numbers, rotation_from_quat, where
from s2r.sources.xmlparse import XmlDoc

__all__ = ["BodyDofs", "JointDof", "keyframe_poses"]

_SIZE = {"free": 7, "ball": 4, "hinge": 1, "slide": 1}


@dataclass
class JointDof:
    """A joint as written: its element, its attributes over its class, the ``<frame>`` pose it sits in."""

    element: ET.Element
    attrs: dict[str, str]
    T_body_frame: FloatArray


@dataclass
class BodyDofs:
    """A body: its parent, its written pose in the parent (``T_parent_body``), mocap flag and joints in order."""

    name: str
    parent: str
    element: ET.Element
    T_parent_body: FloatArray
    mocap: bool
    joints: list[JointDof] = field(default_factory=list)


def _find_key(doc: XmlDoc, key: str) -> ET.Element:
    keys = [k for node in doc.root.findall("keyframe") for k in node.findall("key")]
    names = [k.get("name", "") for k in keys]
    if key in names:
        return keys[names.index(key)]
    if key.isdigit() and int(key) < len(keys):
        return keys[int(key)]
    listed = ", ".join(f"{i}" + (f" ({n})" if n else "") for i, n in enumerate(names)) or "none"
    raise SourceError(f"no keyframe {key!r}; keyframes: {listed}", path=doc.path, field="--keyframe",
                      hint="pass a keyframe index (0 is the first <key>) or name")


def _turn(axis: FloatArray, angle: float) -> FloatArray:
    return rotation_from_quat(np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * axis]))


def _motion(doc: XmlDoc, dof: JointDof, values: list[float], compiler: Compiler) -> FloatArray:
    """The joint's motion ``D`` (the body's pose after it = before it @ D), in the body's frame."""
    kind = dof.attrs.get("type", "hinge")
    frame = dof.T_body_frame
    p = frame[:3, :3] @ np.array(numbers(doc, dof.element, "pos", dof.attrs.get("pos", "0 0 0"), 3)) + frame[:3, 3]
    if kind == "ball":
        R = rotation_from_quat(np.array(values))
    else:
        axis = frame[:3, :3] @ np.array(numbers(doc, dof.element, "axis", dof.attrs.get("axis", "0 0 1"), 3))
        norm = float(np.linalg.norm(axis))
        if norm < 1e-14:
            raise SourceError("joint axis is zero", path=doc.path, field=where(doc, dof.element, "axis"))
        ref = numbers(doc, dof.element, "ref", dof.attrs.get("ref", "0"), 1)[0]
        ref = math.radians(ref) if kind == "hinge" and compiler.degree else ref
        if kind == "slide":
            return make_transform(np.eye(3), axis / norm * (values[0] - ref))
        R = _turn(axis / norm, values[0] - ref)
    return make_transform(R, p - R @ p)


def _split(doc: XmlDoc, key: ET.Element, bodies: list[BodyDofs]) -> list[list[float]] | None:
    """The key's ``qpos`` cut joint by joint (None without a ``qpos``)."""
    dofs = [d for body in bodies for d in body.joints]
    sizes = [_SIZE.get(d.attrs.get("type", "hinge"), 0) for d in dofs]
    if key.get("qpos") is None:
        return None
    values = list(numbers(doc, key, "qpos", key.get("qpos", ""), sum(sizes)))
    return [values[sum(sizes[:i]):sum(sizes[:i + 1])] for i in range(len(sizes))]


def keyframe_poses(doc: XmlDoc, bodies: list[BodyDofs], key: str, compiler: Compiler) -> dict[str, FloatArray]:
    """``T_parent_body`` of every body at keyframe ``key`` (index or name).

    Raises:
        SourceError: no such keyframe, a ``qpos`` / ``mpos`` / ``mquat`` of the wrong length.
    """
    element = _find_key(doc, key)
    chunks = _split(doc, element, bodies)
    mocap = [b for b in bodies if b.mocap]
    mpos = numbers(doc, element, "mpos", element.get("mpos", ""), 3 * len(mocap)) if element.get("mpos") else None
    mquat = numbers(doc, element, "mquat", element.get("mquat", ""), 4 * len(mocap)) if element.get("mquat") else None
    poses: dict[str, FloatArray] = {}
    index = 0
    for body in bodies:
        T = body.T_parent_body
        if body.mocap:
            m = mocap.index(body)
            R = rotation_from_quat(np.array(mquat[4 * m:4 * m + 4])) if mquat else T[:3, :3]
            T = make_transform(R, mpos[3 * m:3 * m + 3] if mpos else T[:3, 3])
        for dof in body.joints:
            values = chunks[index] if chunks is not None else None
            index += 1
            if values is None:
                continue
            if dof.attrs.get("type") == "free":
                T = make_transform(rotation_from_quat(np.array(values[3:])), values[:3])
            else:
                T = T @ _motion(doc, dof, values, compiler)
        poses[body.name] = T
    return poses
