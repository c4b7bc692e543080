"""Read a robot description (URDF, xacro, SDF) and pick its stereo pair; the optical-frame geometry."""

from __future__ import annotations

import logging
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from s2r.errors import SourceError
from s2r.fileio import protect_read_files, read_text_file
from s2r.geometry import T_LINK_OPTICAL, invert_transform
from s2r.sources.description import CameraSpec, Description, FloatArray, JointSpec, SkippedInclude
from s2r.sources.includes import shown
from s2r.sources.kinematics import KinematicTree
from s2r.sources.mjcf.reader import parse_mjcf
from s2r.sources.sdf.include import expand_includes
from s2r.sources.sdf.reader import parse_sdf
from s2r.sources.simulator import infer_simulator
from s2r.sources.urdf.reader import parse_urdf
from s2r.sources.urdf.xacro import XacroExpansion, expand_xacro_files, is_xacro
from s2r.sources.xmlparse import XmlDoc, parse_xml

__all__ = ["StereoPair", "check_skipped_includes", "load_description", "log_notes", "optical_pose", "select_pair",
           "stereo_pair"]

logger = logging.getLogger(__name__)
_NO_CAMERA_HINT = ("add a <sensor type='camera'> inside <gazebo reference='LINK'> (URDF) or inside a <link> (SDF)")
_NO_MJCF_CAMERA_HINT = ("add two <camera name='...' pos='...' fovy='...' resolution='W H'/> inside the <body> of "
                        "the camera link (or write the pair with s2r profile export-mujoco PROFILE and <include> it)")


@dataclass(frozen=True)
class StereoPair:
    """The chosen cameras and ``T_left_right``: the right OPTICAL frame's pose in the left one (metres)."""

    left: CameraSpec
    right: CameraSpec
    T_left_right: FloatArray
    movable_joints: tuple[JointSpec, ...]


def load_description(path: str | Path, *, xacro_args: Mapping[str, str] | None = None,
                     package_paths: Sequence[Path] = (), env: Mapping[str, str] | None = None,
                     keyframe: str | None = None) -> Description:
    """Parse a ``.urdf``, ``.xacro`` / ``.urdf.xacro``, ``.sdf`` / ``.world`` or MJCF file into a :class:`Description`.

    An MJCF model (``<mujoco>`` root, :mod:`s2r.sources.mjcf.reader`) is read at its initial state, or at the
    ``<keyframe>`` ``keyframe`` names (index or name).

    A file of any name that declares the xacro namespace (``robot.gazebo``) is expanded with xacro; SDF
    ``<include>`` of ``model://`` URIs is resolved through ``package_paths`` and GZ_SIM_RESOURCE_PATH /
    GAZEBO_MODEL_PATH (:mod:`s2r.sources.sdf.include`). ``env`` is what xacro's ``$(env)`` / ``$(optenv)`` see
    (``--env NAME=VALUE``); the machine's environment is never read for them.

    Raises:
        SourceError: missing file, xacro failure, malformed XML, unknown root element, missing links.
    """
    source = Path(path)
    text = read_text_file(source, error=SourceError)
    uses_xacro = is_xacro(source) or "xmlns:xacro" in text or "<xacro:" in text  # .gazebo, .xacro.sdf, ...
    expansion = (expand_xacro_files(source, xacro_args=xacro_args, package_paths=package_paths, env=env)
                 if uses_xacro else XacroExpansion(text))
    expanded = expansion.text
    doc = parse_xml(expanded, source)
    if doc.root.tag == "robot":
        _check_legacy_macro_calls(doc, text, expansion)
        description = parse_urdf(doc)
    elif doc.root.tag in ("sdf", "model", "world"):
        included, skipped = expand_includes(doc, package_paths)
        try:
            description = parse_sdf(doc)
        except SourceError as exc:  # a link of a model that is not here: the include is the cause, not the link
            raise _from_missing_include(exc, skipped) from None
        description.included_files, description.skipped_includes = included, skipped
    elif doc.root.tag == "mujoco":
        description = parse_mjcf(doc, keyframe=keyframe)
    else:
        raise SourceError(f"unknown root element <{doc.root.tag}>", path=source, field=f"<{doc.root.tag}>",
                          hint="expected a URDF <robot>, an <sdf> document or a MuJoCo <mujoco> model")
    if keyframe is not None and doc.root.tag != "mujoco":
        raise SourceError("--keyframe is for MuJoCo (MJCF) models", path=source, field="--keyframe",
                          hint="leave it out for URDF / SDF")
    description.source_text, description.expanded_text = text, expanded
    # the files its includes read are inputs of the running command: no output may be one of them
    protect_read_files([*description.included_files, *(Path(p) for p, _ in expansion.included)])
    description.simulator = infer_simulator(doc, lines=not uses_xacro)
    KinematicTree(description)  # joint loops are reported before anything else looks at the cameras
    return description


def _from_missing_include(exc: SourceError, skipped: Sequence[SkippedInclude]) -> SourceError:
    """``exc`` (a link no <link> declares) named as what it is when a skipped ``<include>`` would have brought it:
    the include, and where s2r looks for models; else ``exc`` itself."""
    candidates = [s for s in skipped if not s.cameraless]
    missing = re.findall(r"'([^']+::[^']+)'", exc.message)
    if not candidates or not missing or not ("names no link" in exc.message or "not declared" in exc.message):
        return exc
    model = missing[0].split("::")[0]
    include = next((s for s in candidates if model in s.uri), candidates[0])
    return SourceError(f"link {missing[0]!r} ({exc.field}) belongs to a model of <include> {shown(include.uri)}, "
                       f"which is not available here: {include.message}", path=include.path, field=include.field,
                       hint=include.hint)


#: Elements a URDF <robot> holds; anything else left after xacro may be an unexpanded (legacy) macro call.
_URDF_CHILDREN = frozenset({"link", "joint", "gazebo", "transmission", "material", "ros2_control", "sensor"})


def _legacy_call_site(tag: str, source: Path, source_text: str, expansion: XacroExpansion) -> tuple[Path, int | None]:
    """The file and line of a legacy ``<tag ...>`` call: the description itself first, then its included files."""
    for path, text in [(source, source_text), *((Path(p), t) for p, t in expansion.included)]:
        for number, line in enumerate(text.splitlines(), start=1):
            if re.search(rf"<{re.escape(tag)}[\s/>]", line) and f"<xacro:{tag}" not in line:
                return path, number
    return source, None


def _check_legacy_macro_calls(doc: XmlDoc, source_text: str, expansion: XacroExpansion) -> None:
    """xacro 2 leaves a macro call without the ``xacro:`` prefix (legacy ROS 1 syntax) as a plain element: name it,
    whether the macro is defined in the description or in a file it includes (``<BB2-08S2C-38 .../>``,
    ``<sensor_d435 .../>``)."""
    macros = expansion.macro_names(source_text)
    for child in doc.root:
        tag = child.tag
        if tag in _URDF_CHILDREN or ":" in tag or "}" in tag:
            continue
        line = doc.line(child)
        if tag not in macros:
            if "xacro" in source_text:
                logger.warning("%s: <%s> (line %s of the expanded XML) is not a URDF element; if it is a macro "
                               "call, write <xacro:%s .../>", doc.path, tag, line, tag)
            continue
        path, source_line = _legacy_call_site(tag, doc.path, source_text, expansion)
        raise SourceError(f"<{tag}> is a legacy macro call without the xacro: prefix, which xacro 2 no longer "
                          "expands", path=path, field=f"<{tag}>" + (f" line {source_line}" if source_line else ""),
                          hint=f"write <xacro:{tag} .../> (the ROS 1 xacro --inorder syntax)")


def _pick(description: Description, query: str, option: str) -> CameraSpec:
    found = [c for c in description.cameras if c.matches(query)]
    names = ", ".join(c.name for c in description.cameras)
    if not found:
        raise SourceError(f"no camera named {query!r}; cameras: {names}", path=description.path, field=option,
                          hint=f"pass {option} with one of the listed names")
    if len(found) > 1:
        raise SourceError(f"{query!r} names {len(found)} cameras ({', '.join(c.name for c in found)})",
                          path=description.path, field=option, hint="use the full sensor/camera name")
    return found[0]


def _side(camera: CameraSpec) -> str | None:
    text = " ".join((camera.camera_name, camera.sensor_name, camera.link)).lower()
    has_left, has_right = bool(re.search("left", text)), bool(re.search("right", text))
    return "left" if has_left and not has_right else "right" if has_right and not has_left else None


def select_pair(description: Description, *, left: str | None = None,
                right: str | None = None) -> tuple[CameraSpec, CameraSpec]:
    """The (left, right) cameras: by name when given, else the only two cameras of the description.

    Without names, two cameras are ordered by their names (``left``/``right``) or else by geometry (the
    right camera is the one further along the left camera's image x axis).
    """
    cameras = description.cameras
    if not cameras:
        macros = re.findall(r"<xacro:macro\s+name\s*=\s*[\"']([^\"']+)[\"']", description.source_text or "")
        if macros and "<sensor" in (description.source_text or ""):  # e.g. PR2's *.gazebo.xacro sensor macros
            raise SourceError(f"no camera sensor found: the file only defines xacro macros ({', '.join(macros)}) "
                              "that nothing calls", path=description.path, field="<xacro:macro>",
                              hint="pass the robot description that calls them (its top-level .urdf.xacro)")
        if "<sensor:camera" in (description.expanded_text or description.source_text or ""):
            raise SourceError("no camera sensor found: <sensor:camera> is the Gazebo 0.x (pre-SDF, ROS diamondback) "
                              "format, which no current Gazebo reads", path=description.path, field="<sensor:camera>",
                              hint="describe the cameras as SDF <sensor type='camera'> (Gazebo classic or gz-sim)")
        switches = sorted(set(re.findall(r"\$\((?:opt)?env\s+([A-Za-z_][A-Za-z0-9_]*)", description.source_text or "")))
        if switches:  # Clearpath: payloads are switched on by environment variables s2r does not read
            listed = ", ".join(switches[:6]) + (", ..." if len(switches) > 6 else "")
            raise SourceError("no camera sensor found", path=description.path, field="<sensor>",
                              hint=f"this description reads environment variables ({listed}) that s2r does not take "
                              "from the machine: pass the ones that switch the cameras on with --env NAME=VALUE "
                              f"(e.g. --env {switches[0]}=1)")
        if description.kind == "mjcf":
            raise SourceError("no <camera> found in the MJCF", path=description.path, field="<camera>",
                              hint=_NO_MJCF_CAMERA_HINT)
        raise SourceError("no camera sensor found", path=description.path, field="<sensor>", hint=_NO_CAMERA_HINT)
    if left is not None and right is not None:
        pair = (_pick(description, left, "--left"), _pick(description, right, "--right"))
        if pair[0] is pair[1]:
            raise SourceError("--left and --right name the same camera", path=description.path, field="--right",
                              hint="name two different cameras")
        return pair
    if len(cameras) != 2 or left is not None or right is not None:
        names = ", ".join(c.name for c in cameras)
        why = f"found {len(cameras)} camera(s): {names}"
        mjcf = description.kind == "mjcf"
        no_camera = _NO_MJCF_CAMERA_HINT if mjcf else _NO_CAMERA_HINT
        raise SourceError(f"cannot choose the stereo pair by itself; {why}", path=description.path,
                          field="<camera>" if mjcf else "<sensor>",
                          hint="pass --left NAME --right NAME with two of the listed cameras" if len(cameras) > 1
                          else "a stereo pair needs two cameras: " + no_camera)
    first, second = cameras
    if _side(first) == "right" and _side(second) == "left":
        return second, first
    if _side(first) is None or _side(second) is None:
        tree = KinematicTree(description)
        T = optical_pose_between(tree, first, second)
        if T[0, 3] < -1e-9:
            return second, first
    return first, second


def optical_pose(camera: CameraSpec) -> FloatArray:
    """``T_link_optical``: the optical frame (z forward, x right, y down) of what Gazebo renders, in the link frame.

    Gazebo (classic and gz-sim) renders along the +x axis of the camera frame (the link frame composed with
    the sensor's and the camera's ``<pose>``), whatever the link is called: the optical frame is always that
    frame rotated by rpy (-pi/2, 0, -pi/2). A sensor on a link named ``*_optical`` whose pose rotation undoes
    the optical rotation (the pointgrey Bumblebee2 / Flea3 macros) therefore comes out as the link itself.
    """
    return camera.T_link_camera @ T_LINK_OPTICAL


def optical_pose_between(tree: KinematicTree, left: CameraSpec, right: CameraSpec) -> FloatArray:
    """``T_left_right`` between the two cameras' optical frames (metres), movable joints at zero."""
    T_links, _ = tree.transform(left.link, right.link)
    return invert_transform(optical_pose(left)) @ T_links @ optical_pose(right)


def check_skipped_includes(description: Description, *, left: str | None = None, right: str | None = None) -> None:
    """Skip (with a note in ``description.notes``, see :func:`log_notes`) the includes that named nothing here when
    they cannot hold a camera asked for: a standard camera-less model (``model://sun``, ``ground_plane``), or any
    model when ``left`` and ``right`` both name cameras defined inline, or (no names) when the file itself defines
    exactly two cameras, the pair. Otherwise (the pair could be in the missing model) the first such include is
    the error.

    Raises:
        SourceError: an include that names nothing here and might hold a camera asked for.
    """
    named_inline = left is not None and right is not None and all(
        any(c.matches(q) for c in description.cameras) for q in (left, right))
    pair_inline = left is None and right is None and len(description.cameras) == 2
    for skipped in description.skipped_includes:
        if not (skipped.cameraless or named_inline or pair_inline):
            raise skipped.error()
    for skipped in description.skipped_includes:
        why = ("a standard model without cameras" if skipped.cameraless else "the cameras asked for are inline"
               if named_inline else "the file defines a stereo pair itself (if this model holds the cameras meant, "
               "pass --package-path with its folder)")
        note = f"skipped <include> {shown(skipped.uri)} ({skipped.field}): not available here, {why}"
        if note not in description.notes:
            description.notes.append(note)


def log_notes(description: Description) -> None:
    """Log what was decided while reading ``description`` (skipped includes), once the result stands: an error
    stays the only line of a failed command."""
    for note in description.notes:
        logger.warning("%s: %s", description.path, note)


def stereo_pair(description: Description, *, left: str | None = None, right: str | None = None) -> StereoPair:
    """Choose the pair and compute its optical-frame geometry; warn about movable joints on the path.

    Includes that named nothing here are skipped or refused first (:func:`check_skipped_includes`)."""
    check_skipped_includes(description, left=left, right=right)
    cam_left, cam_right = select_pair(description, left=left, right=right)
    tree = KinematicTree(description)
    _, movable = tree.transform(cam_left.link, cam_right.link)
    for joint in movable:
        at = description.joint_state or "position 0"
        logger.warning("%s: joint %r (%s) between the camera links is taken at %s", description.path,
                       joint.name, joint.type, at)
    T = optical_pose_between(tree, cam_left, cam_right)
    return StereoPair(cam_left, cam_right, T, tuple(movable))
