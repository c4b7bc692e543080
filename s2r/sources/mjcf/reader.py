"""MJCF (MuJoCo's ``<mujoco>`` models) to a :class:`Description`: bodies, their joints and the cameras.

Read as MuJoCo compiles it: ``<include>`` expanded first (:mod:`s2r.sources.mjcf.include`), ``<compiler angle
eulerseq>`` (:mod:`s2r.sources.mjcf.pose`), ``<default>`` classes (nested classes inherit; an element takes its
``class``, else the nearest ``childclass`` of an enclosing body or frame, else ``main``), ``<frame>`` elements
(their pose composes into their children) and every ``<worldbody>``. Each body becomes a pseudo-joint from its
parent body (type ``fixed``, or its first joint's type: hinge, slide, ball, free), so the kinematics are the same
as URDF's; the pose is the model's initial state (qpos0: the model as written), or a ``<keyframe>``'s
(:mod:`s2r.sources.mjcf.keyframe`). Cameras (:mod:`s2r.sources.mjcf.camera`) become :class:`CameraSpec` objects whose
``T_link_camera`` is expressed, like Gazebo's, as the optical frame times ``T_LINK_OPTICAL``'s inverse, so lint and
the profile builder need no MJCF branch for the geometry.
"""

from __future__ import annotations

import logging
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field, replace

import numpy as np

from s2r.errors import SourceError
from s2r.geometry import T_LINK_OPTICAL, invert_transform, make_transform
from s2r.sources.description import CameraSpec, Description, FloatArray, JointSpec, LensIntrinsics
from s2r.sources.mjcf.camera import MODES, camera_intrinsics, offscreen_size
from s2r.sources.mjcf.defaults import Defaults, read_defaults
from s2r.sources.mjcf.include import expand_includes
from s2r.sources.mjcf.keyframe import BodyDofs, JointDof, keyframe_poses
from s2r.sources.mjcf.pose import Compiler, local_pose, numbers, read_compiler, where
from s2r.sources.xmlparse import XmlDoc

__all__ = ["SENSOR_TYPE", "T_MJCAM_OPTICAL", "parse_mjcf"]

logger = logging.getLogger(__name__)
#: ``CameraSpec.sensor_type`` of a camera read from MJCF.
SENSOR_TYPE = "mjcf"
#: The OpenCV optical frame (z forward, y down) in MuJoCo's camera frame (looks along -z, +y up): pi about x.
T_MJCAM_OPTICAL: FloatArray = make_transform(np.diag([1.0, -1.0, -1.0]), np.zeros(3))
_SKIPPED = frozenset({"geom", "site", "light", "inertial", "plugin", "composite", "flexcomp"})


@dataclass
class _Camera:
    element: ET.Element
    attrs: dict[str, str]
    body: str
    T_body_frame: FloatArray
    T_body_cam: FloatArray
    index: int


@dataclass
class _Tree:
    doc: XmlDoc
    compiler: Compiler
    defaults: Defaults
    links: dict[str, int | None] = field(default_factory=dict)
    joints: list[JointSpec] = field(default_factory=list)
    world: dict[str, FloatArray] = field(default_factory=dict)
    cameras: list[_Camera] = field(default_factory=list)
    bodies: list[BodyDofs] = field(default_factory=list)
    world0: dict[str, FloatArray] = field(default_factory=dict)
    keyframe: str | None = None


def _line(doc: XmlDoc, element: ET.Element) -> int | None:
    """The element's line in the scene file (None for one read from an included file: lint names the scene)."""
    return None if id(element) in doc.files else doc.line(element)


def _body_name(doc: XmlDoc, body: ET.Element) -> str:
    return body.get("name") or f"body_line_{doc.line(body)}"


def _dof(tree: _Tree, body: str, element: ET.Element, T_body_frame: FloatArray, active: str) -> None:
    """Record a ``<joint>`` / ``<freejoint>`` of ``body`` (for keyframes and the movable-joint warning)."""
    attrs = {"type": "free"} if element.tag == "freejoint" else tree.defaults.attrs(tree.doc, element, "joint",
                                                                                     active)
    dofs = next(b for b in tree.bodies if b.name == body)
    dofs.joints.append(JointDof(element, attrs, T_body_frame))


def _walk(tree: _Tree, node: ET.Element, body: str, T_body_frame: FloatArray, active: str) -> None:
    """Visit the children of ``node`` (a body, a frame or the worldbody) that belong to body ``body``."""
    doc = tree.doc
    for child in node:
        if child.tag in _SKIPPED:
            continue
        if child.tag == "frame":
            inner = tree.defaults.childclass(doc, child, active)
            _walk(tree, child, body, T_body_frame @ local_pose(doc, child, tree.compiler), inner)
        elif child.tag == "body":
            _body(tree, child, body, T_body_frame, active)
        elif child.tag in ("joint", "freejoint") and body != "world":
            _dof(tree, body, child, T_body_frame, active)
        elif child.tag == "camera":
            attrs = tree.defaults.attrs(doc, child, "camera", active)
            T = T_body_frame @ local_pose(doc, child, tree.compiler, tree.defaults.camera_pose(doc, child, active))
            tree.cameras.append(_Camera(child, attrs, body, T_body_frame, T, len(tree.cameras)))
        elif child.tag == "replicate" and child.find(".//camera") is not None:
            raise SourceError("cameras inside <replicate> are not read by s2r", path=doc.path,
                              field=where(doc, child), hint="write the cameras' bodies out (MuJoCo's saved XML, "
                              "mj_saveLastXML, has no replicate)")
        elif child.tag == "attach":
            logger.warning("%s: %s: the cameras of an attached model are not read (s2r reads this file only)",
                           doc.path, where(doc, child))


def _body(tree: _Tree, element: ET.Element, parent: str, T_parent_frame: FloatArray, active: str) -> None:
    doc = tree.doc
    name = _body_name(doc, element)
    if name in tree.links:
        raise SourceError(f"two bodies are named {name!r}", path=doc.path, field=where(doc, element),
                          hint="give each body a unique name")
    inner = tree.defaults.childclass(doc, element, active)
    T = T_parent_frame @ local_pose(doc, element, tree.compiler)
    tree.links[name] = _line(doc, element)
    tree.world[name] = tree.world[parent] @ T
    dofs = BodyDofs(name, parent, element, T, element.get("mocap") == "true")
    tree.bodies.append(dofs)
    _walk(tree, element, name, np.eye(4), inner)
    kind = dofs.joints[0].attrs.get("type", "hinge") if dofs.joints else "mocap" if dofs.mocap else "fixed"
    tree.joints.append(JointSpec(name=f"<body {name}>", type=kind, parent=parent, child=name, T_parent_child=T,
                                 line=_line(doc, element)))


def _target_orientation(tree: _Tree, camera: _Camera) -> FloatArray:
    """``T_body_cam`` of a ``targetbody`` camera at the initial state: -z towards the target body's origin, x
    orthogonal to the world's z (MuJoCo's ``mj_camlight``)."""
    doc, element = tree.doc, camera.element
    target = camera.attrs.get("target")
    if target is None or target not in tree.world:
        raise SourceError(f"mode targetbody needs a target body; {target!r} is not a body", path=doc.path,
                          field=where(doc, element, "target"), hint="set target to the name of a body")
    T_world_cam = tree.world[camera.body] @ camera.T_body_cam
    z = T_world_cam[:3, 3] - tree.world[target][:3, 3]
    x = np.cross([0.0, 0.0, 1.0], z)
    if float(np.linalg.norm(z)) < 1e-9 or float(np.linalg.norm(x)) < 1e-9 * max(1.0, float(np.linalg.norm(z))):
        raise SourceError("a targetbody camera straight above, below or at its target has no defined orientation",
                          path=doc.path, field=where(doc, element, "mode"), hint="move the camera or the target")
    z, x = z / np.linalg.norm(z), x / np.linalg.norm(x)
    R = np.column_stack([x, np.cross(z, x), z])
    return invert_transform(tree.world[camera.body]) @ make_transform(R, T_world_cam[:3, 3])


def _pose_for_mode(tree: _Tree, camera: _Camera) -> tuple[FloatArray, str | None]:
    """The camera pose in its body at the model's initial state, and a warning when it moves with the state."""
    doc, element = tree.doc, camera.element
    mode = camera.attrs.get("mode", "fixed")
    if mode not in MODES:
        raise SourceError(f"unknown camera mode {mode!r}", path=doc.path, field=where(doc, element, "mode"),
                          hint=f"one of {', '.join(MODES)}")
    if mode == "fixed":
        return camera.T_body_cam, None
    if mode == "targetbodycom":
        raise SourceError("mode targetbodycom aims at a subtree's centre of mass, which s2r does not compute",
                          path=doc.path, field=where(doc, element, "mode"),
                          hint="use mode='targetbody' or 'fixed' for the stereo cameras")
    if mode == "trackcom" and tree.keyframe is not None:
        raise SourceError("mode trackcom follows a subtree's centre of mass, which s2r does not compute",
                          path=doc.path, field=where(doc, element, "mode"),
                          hint="read it at the initial state (leave out --keyframe), or use mode='track'")
    T = _target_orientation(tree, camera) if mode == "targetbody" else _tracked(tree, camera)
    where_read = "the model's initial state (qpos0; pass --keyframe N for a keyframe's)" if tree.keyframe is None \
        else f"keyframe {tree.keyframe}"
    return T, f"camera mode {mode!r} moves with the simulation state: read at {where_read}"


def _tracked(tree: _Tree, camera: _Camera) -> FloatArray:
    """A ``track`` camera: its world rotation and its offset from the body's origin stay those of the initial
    state (MuJoCo's ``cam_mat0`` and ``cam_pos0``), wherever the body has moved."""
    if tree.keyframe is None:
        return camera.T_body_cam
    T0 = tree.world0[camera.body] @ camera.T_body_cam
    position = tree.world[camera.body][:3, 3] + T0[:3, 3] - tree.world0[camera.body][:3, 3]
    return invert_transform(tree.world[camera.body]) @ make_transform(T0[:3, :3], position)


def _spec(tree: _Tree, camera: _Camera, offscreen: tuple[int, int],
          clip: tuple[float | None, float | None]) -> CameraSpec:
    doc, element = tree.doc, camera.element
    k = camera_intrinsics(doc, element, camera.attrs, offscreen)
    T_body_cam, warning = _pose_for_mode(tree, camera)
    notes = [warning] if warning else []
    if not k.resolution_given:
        notes.append(f"camera has no resolution: it renders at the offscreen buffer size {k.width}x{k.height} "
                     "(<visual><global offwidth offheight>)")
    name = element.get("name") or f"camera{camera.index}"
    line = _line(doc, element)
    return CameraSpec(
        name=name, sensor_name=name, camera_name=name, sensor_type=SENSOR_TYPE, link=camera.body,
        T_link_camera=T_body_cam @ T_MJCAM_OPTICAL @ invert_transform(T_LINK_OPTICAL), width=k.width,
        height=k.height, hfov_rad=2.0 * math.atan(k.width / (2.0 * k.fx)), clip_near_m=clip[0], clip_far_m=clip[1],
        update_rate_hz=None, distortion=None, noise=None,
        lens=LensIntrinsics(k.fx, k.fy, k.cx + 0.5, k.cy + 0.5, line=line), plugin=None,
        T_link_sensor=camera.T_body_frame, lines={"sensor": line, "camera": line, "pose": line},
        remarks=tuple(notes), intrinsics_form=k.form,
    )


def _clip(doc: XmlDoc) -> tuple[float | None, float | None]:
    """Near and far clip (metres) when ``<statistic extent>`` is written (MuJoCo scales ``<map znear zfar>`` by
    the model's extent, which otherwise depends on the geometry)."""
    extent = None
    for node in doc.root.iter("statistic"):
        if "extent" in node.attrib:
            extent = numbers(doc, node, "extent", node.get("extent", ""), 1)[0]
    if extent is None or extent <= 0:
        return None, None
    near, far = 0.01, 50.0
    for node in doc.root.iter("map"):
        near = numbers(doc, node, "znear", node.get("znear", str(near)), 1)[0]
        far = numbers(doc, node, "zfar", node.get("zfar", str(far)), 1)[0]
    return near * extent, far * extent


def parse_mjcf(doc: XmlDoc, *, keyframe: str | None = None) -> Description:
    """Bodies (as pseudo-joints from their parent body), joints and cameras of an MJCF document (``<mujoco>``).

    ``keyframe``: the index or name of a ``<keyframe><key>`` whose joint positions place the bodies (default:
    the model as written, MuJoCo's qpos0). Raises SourceError naming the file and element for anything MuJoCo would
    refuse or s2r cannot read."""
    if doc.root.tag != "mujoco":
        raise SourceError(f"expected a <mujoco> root element, got <{doc.root.tag}>", path=doc.path,
                          field=f"<{doc.root.tag}>")
    included = expand_includes(doc)
    tree = _Tree(doc, read_compiler(doc), read_defaults(doc))
    tree.links["world"], tree.world["world"] = doc.line(doc.root), np.eye(4)
    for worldbody in doc.root.findall("worldbody"):
        _walk(tree, worldbody, "world", np.eye(4), tree.defaults.childclass(doc, worldbody, "main"))
    tree.world0 = dict(tree.world)
    if keyframe is not None:
        _apply_keyframe(tree, keyframe)
    offscreen = offscreen_size(doc)
    clip = _clip(doc)
    specs = [_spec(tree, camera, offscreen, clip) for camera in tree.cameras]
    state = "the model's initial state" if keyframe is None else f"keyframe {keyframe}"
    return Description(path=doc.path, kind="mjcf", links=tree.links, joints=tree.joints, cameras=specs,
                       joint_state=state, included_files=included)


def _apply_keyframe(tree: _Tree, keyframe: str) -> None:
    """Move every body to its pose at ``keyframe`` (parents come before children in ``tree.bodies``)."""
    poses = keyframe_poses(tree.doc, tree.bodies, keyframe, tree.compiler)
    tree.joints = [replace(j, T_parent_child=poses[j.child]) for j in tree.joints]
    for body in tree.bodies:
        tree.world[body.name] = tree.world[body.parent] @ poses[body.name]
    tree.keyframe = keyframe
