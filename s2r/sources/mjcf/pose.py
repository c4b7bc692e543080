"""MJCF poses: numbers in attributes, ``<compiler>`` settings and the five orientation forms, as MuJoCo reads them.

Every frame-bearing element (body, frame, camera) has ``pos`` (metres, default 0) and at most ONE of ``quat``
(w first, normalised), ``axisangle`` (axis, angle), ``euler`` (three angles about the axes ``<compiler
eulerseq>`` names, default ``xyz``), ``xyaxes`` (the frame's x and y axes; y is made orthogonal) and ``zaxis``
(the minimal rotation taking +z onto it). Angles are in ``<compiler angle>`` units (degree by default); in
``eulerseq`` a lowercase letter is an axis that turns with the frame (intrinsic, the quaternion is post-multiplied)
and an uppercase letter a fixed parent axis (extrinsic, pre-multiplied): MuJoCo's ``ResolveOrientation``
(src/user/user_objects.cc), which the tests check against MuJoCo itself.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from s2r.errors import SourceError
from s2r.geometry import make_transform
from s2r.sources.description import FloatArray
from s2r.sources.xmlparse import XmlDoc

__all__ = ["MAX_POSE_VALUE", "ORIENTATIONS", "Compiler", "local_pose", "numbers", "quat_from_rotation", "read_compiler",
           "rotation_from_quat",
           "where"]

#: Largest coordinate accepted in a position or angle (metres, degrees or radians): as for URDF / SDF poses.
MAX_POSE_VALUE = 1e6
#: The orientation attributes, of which an element (or a defaults class) may set at most one.
ORIENTATIONS = ("quat", "axisangle", "xyaxes", "zaxis", "euler")
_EPS = 1e-14  # MuJoCo's mjEPS: a vector shorter than this cannot be normalised


@dataclass(frozen=True)
class Compiler:
    """The ``<compiler>`` settings that change how poses read: angle unit and Euler sequence."""

    degree: bool = True
    eulerseq: str = "xyz"


def where(doc: XmlDoc, element: ET.Element, attribute: str | None = None) -> str:
    """``<tag name='x'> line N: attribute`` (``line N of part.xml`` for an element from an included file): the place
    a message names."""
    name = element.get("name")
    text = f"<{element.tag}" + (f" name={name!r}" if name else "") + ">"
    line = doc.line(element)
    text += f" line {line}" if line else ""
    origin = doc.files.get(id(element))
    if origin is not None:
        text += f" of {origin.name}" if line else f" in {origin.name}"
    return text + (f": {attribute}" if attribute else "")


def numbers(doc: XmlDoc, element: ET.Element, attribute: str, text: str, count: int, *,
            limit: float = MAX_POSE_VALUE) -> tuple[float, ...]:
    """``count`` finite numbers from an attribute's ``text``, each within +-``limit``; SourceError naming the
    element and attribute otherwise."""
    parts = text.split()
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise SourceError(f"expected {count} number(s), got {text[:80]!r}", path=doc.path,
                          field=where(doc, element, attribute), hint=f"write {count} space-separated numbers")
    if any(abs(v) > limit for v in values):
        raise SourceError(f"a value beyond {limit:g} in {text[:80]!r}", path=doc.path,
                          field=where(doc, element, attribute), hint="positions are metres, angles degrees/radians")
    return values


def read_compiler(doc: XmlDoc) -> Compiler:
    """The model's compiler settings; repeated ``<compiler>`` sections apply in order (the last setting wins)."""
    degree, seq = True, "xyz"
    for node in doc.root.iter("compiler"):
        angle = node.get("angle")
        if angle is not None:
            if angle not in ("degree", "radian"):
                raise SourceError(f"angle must be degree or radian, got {angle!r}", path=doc.path,
                                  field=where(doc, node, "angle"))
            degree = angle == "degree"
        value = node.get("eulerseq")
        if value is not None:
            if len(value) != 3 or any(c not in "xyzXYZ" for c in value):
                raise SourceError(f"eulerseq must be 3 letters from x y z X Y Z, got {value!r}", path=doc.path,
                                  field=where(doc, node, "eulerseq"))
            seq = value
    return Compiler(degree=degree, eulerseq=seq)


def _qmul(a: FloatArray, b: FloatArray) -> FloatArray:
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def _qmat(q: FloatArray) -> FloatArray:
    """Rotation matrix of a unit quaternion (w, x, y, z)."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _unit(doc: XmlDoc, element: ET.Element, attribute: str, v: FloatArray, what: str) -> FloatArray:
    norm = float(np.linalg.norm(v))
    if norm < _EPS:
        raise SourceError(f"{what} is too small to give a direction", path=doc.path,
                          field=where(doc, element, attribute), hint="give a non-zero vector")
    return np.asarray(v / norm, dtype=np.float64)


def _euler(angles: tuple[float, ...], compiler: Compiler) -> FloatArray:
    q = np.array([1.0, 0.0, 0.0, 0.0])
    for letter, angle in zip(compiler.eulerseq, angles, strict=True):
        a = math.radians(angle) if compiler.degree else angle
        axis = "xyz".index(letter.lower())
        turn = np.array([math.cos(a / 2), 0.0, 0.0, 0.0])
        turn[1 + axis] = math.sin(a / 2)
        q = _qmul(q, turn) if letter.islower() else _qmul(turn, q)  # moving axes post-multiply, fixed pre-multiply
    return _qmat(q / np.linalg.norm(q))


def _zaxis(doc: XmlDoc, element: ET.Element, values: tuple[float, ...]) -> FloatArray:
    z = _unit(doc, element, "zaxis", np.array(values), "zaxis")
    axis = np.cross([0.0, 0.0, 1.0], z)
    s = float(np.linalg.norm(axis))
    axis = axis / s if s >= 1e-10 else np.array([1.0, 0.0, 0.0])  # z or -z: turn about x (MuJoCo's choice)
    angle = math.atan2(s, float(z[2]))
    return _qmat(np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * axis]))


def _xyaxes(doc: XmlDoc, element: ET.Element, values: tuple[float, ...]) -> FloatArray:
    x = _unit(doc, element, "xyaxes", np.array(values[:3]), "the x axis of xyaxes")
    y = np.array(values[3:]) - x * float(np.dot(x, values[3:]))
    y = _unit(doc, element, "xyaxes", y, "the y axis of xyaxes (after making it orthogonal to x)")
    z = _unit(doc, element, "xyaxes", np.cross(x, y), "cross(xaxis, yaxis)")
    return np.column_stack([x, y, z])


def _rotation(doc: XmlDoc, element: ET.Element, kind: str, text: str, compiler: Compiler) -> FloatArray:
    if kind == "quat":
        q = np.array(numbers(doc, element, kind, text, 4))
        return _qmat(_unit(doc, element, kind, q, "quat (a zero quaternion)"))
    if kind == "axisangle":
        values = numbers(doc, element, kind, text, 4)
        axis = _unit(doc, element, kind, np.array(values[:3]), "the axis of axisangle")
        a = math.radians(values[3]) if compiler.degree else values[3]
        return _qmat(np.concatenate([[math.cos(a / 2)], math.sin(a / 2) * axis]))
    if kind == "euler":
        return _euler(numbers(doc, element, kind, text, 3), compiler)
    if kind == "xyaxes":
        return _xyaxes(doc, element, numbers(doc, element, kind, text, 6))
    return _zaxis(doc, element, numbers(doc, element, kind, text, 3))


def local_pose(doc: XmlDoc, element: ET.Element, compiler: Compiler,
               defaults: Mapping[str, str] | None = None) -> FloatArray:
    """4x4 pose (metres) of ``element``'s frame in its parent's: ``pos`` and its one orientation attribute.

    ``defaults``: attributes of the element's defaults class (cameras): an orientation the element does not
    write comes from the class, and so does ``pos``.

    Raises:
        SourceError: two orientation attributes on one element, a malformed or degenerate value.
    """
    given = [k for k in ORIENTATIONS if k in element.attrib]
    if len(given) > 1:
        raise SourceError(f"multiple orientation attributes ({', '.join(given)})", path=doc.path,
                          field=where(doc, element), hint="keep exactly one of quat, axisangle, xyaxes, zaxis, euler")
    source: Mapping[str, str] = element.attrib
    if not given and defaults:
        given = [k for k in ORIENTATIONS if k in defaults]
        source = defaults
    R = _rotation(doc, element, given[0], source[given[0]], compiler) if given else np.eye(3)
    pos_text = element.get("pos", (defaults or {}).get("pos", "0 0 0"))
    return make_transform(R, numbers(doc, element, "pos", pos_text, 3))


def quat_from_rotation(R: FloatArray) -> tuple[float, float, float, float]:
    """Unit quaternion (w, x, y, z), w >= 0, of a 3x3 rotation matrix (MuJoCo's ``quat`` attribute order)."""
    m = np.asarray(R, dtype=np.float64)
    trace = float(np.trace(m))
    if trace > 0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = [0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s]
    else:
        i = int(np.argmax(np.diag(m)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(max(1e-300, 1.0 + m[i, i] - m[j, j] - m[k, k]))
        q = [0.0] * 4
        q[0] = (m[k, j] - m[j, k]) / s
        q[1 + i], q[1 + j], q[1 + k] = 0.25 * s, (m[j, i] + m[i, j]) / s, (m[k, i] + m[i, k]) / s
    v = np.array(q) / np.linalg.norm(q)
    v = -v if v[0] < 0 else v
    return float(v[0]), float(v[1]), float(v[2]), float(v[3])


def rotation_from_quat(q: FloatArray) -> FloatArray:
    """Rotation matrix of a quaternion (w, x, y, z), normalised; identity for a zero one (as MuJoCo normalises)."""
    norm = float(np.linalg.norm(q))
    return np.eye(3) if norm < _EPS else _qmat(np.asarray(q, dtype=np.float64) / norm)
