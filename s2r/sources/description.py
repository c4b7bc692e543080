"""What s2r reads from a robot description: links, joints and camera sensors, with source lines.

Poses are 4x4 transforms in metres named ``T_a_b`` (pose of frame ``b`` in frame ``a``). A Gazebo camera
frame looks along its +x axis (image right = -y, image down = -z); its optical frame is that frame
rotated by rpy (-pi/2, 0, -pi/2) (:data:`s2r.geometry.R_LINK_OPTICAL`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from s2r.errors import SourceError

if TYPE_CHECKING:
    from s2r.sources.simulator import SimulatorGuess

__all__ = ["CameraSpec", "Description", "GazeboDistortion", "JointSpec", "LensIntrinsics", "NoiseSpec", "PluginSpec",
           "SkippedInclude"]

FloatArray = NDArray[np.float64]
#: Joint types that move; the path through them is evaluated at joint position zero.
MOVABLE_JOINTS = frozenset({"revolute", "continuous", "prismatic", "planar", "floating", "ball", "universal",
                            "revolute2", "screw", "gearbox", "hinge", "slide", "free", "mocap"})
#: Link-name endings that mark a link as an optical frame already (z forward, x right, y down).
OPTICAL_SUFFIXES = ("_optical", "_optical_frame", "_optical_link")


@dataclass(frozen=True)
class LensIntrinsics:
    """``<lens><intrinsics>`` (gz-sim and Gazebo classic): focal lengths, principal point (OpenCV's + 0.5) and skew,
    pixels."""

    fx: float
    fy: float
    cx: float
    cy: float
    s: float = 0.0
    line: int | None = None


@dataclass(frozen=True)
class GazeboDistortion:
    """``<distortion>`` of a camera: Brown coefficients in Gazebo's image-size-normalised units and the
    distortion centre in texture coordinates (0.5, 0.5 = image centre)."""

    k1: float = 0.0
    k2: float = 0.0
    k3: float = 0.0
    p1: float = 0.0
    p2: float = 0.0
    center: tuple[float, float] = (0.5, 0.5)
    line: int | None = None
    #: Gazebo classic's ``<ignition:legacy_mode>`` (default true): false = coefficients in the W/f-scaled units.
    legacy_mode: bool = True

    @property
    def is_zero(self) -> bool:
        """True when no coefficient is set."""
        return not any((self.k1, self.k2, self.k3, self.p1, self.p2))


@dataclass(frozen=True)
class NoiseSpec:
    """Image ``<noise>``: type, mean and standard deviation on intensities in [0, 1]."""

    type: str
    mean: float
    stddev: float


@dataclass(frozen=True)
class PluginSpec:
    """A ROS camera plugin attached to a sensor (gazebo_ros camera / multicamera)."""

    filename: str
    hack_baseline: float | None = None
    hack_baseline_line: int | None = None
    hack_baseline_tag: str = ""
    focal_length: float | None = None
    focal_length_line: int | None = None
    frame_name: str | None = None
    camera_name: str | None = None
    line: int | None = None
    #: ``<borderCrop>`` (gazebo_ros, default true): crop a barrel-distorted image (k1 < 0), magnifying it.
    border_crop: bool = True


@dataclass(frozen=True, eq=False)
class CameraSpec:
    """One camera of a sensor (a multicamera sensor has several), as written in the description.

    ``T_link_camera`` is the pose (metres) of the Gazebo camera frame (+x forward) in its link's frame:
    the sensor ``<pose>`` composed with the camera's own ``<pose>``.
    """

    name: str
    sensor_name: str
    camera_name: str
    sensor_type: str
    link: str
    T_link_camera: FloatArray
    width: int
    height: int
    hfov_rad: float
    clip_near_m: float | None
    clip_far_m: float | None
    update_rate_hz: float | None
    distortion: GazeboDistortion | None
    noise: NoiseSpec | None
    lens: LensIntrinsics | None
    plugin: PluginSpec | None
    T_link_sensor: FloatArray | None = None
    index_in_sensor: int = 0
    cameras_in_sensor: int = 1
    lines: dict[str, int | None] = field(default_factory=dict)
    #: What the reader noticed about this camera and the user should hear when it is chosen (MJCF: a camera mode
    #: that moves with the simulation, an image size taken from the offscreen buffer).
    remarks: tuple[str, ...] = ()
    #: How the intrinsics were given (MJCF: ``fovy``, ``sensorsize + focalpixel + ...``); empty for Gazebo sensors.
    intrinsics_form: str = ""

    @property
    def link_is_optical(self) -> bool:
        """True when the camera's link is named as an optical frame (``*_optical``, ``*_optical_frame``)."""
        return self.link.endswith(OPTICAL_SUFFIXES)

    def matches(self, query: str) -> bool:
        """Whether ``query`` names this camera: its full name, camera name, sensor name or link."""
        names = {self.name, self.link}
        if self.cameras_in_sensor == 1:
            names.add(self.sensor_name)
        if self.camera_name:
            names.add(self.camera_name)
        return query in names


@dataclass(frozen=True, eq=False)
class JointSpec:
    """A joint: ``T_parent_child`` is the child link's pose in the parent link at joint position zero."""

    name: str
    type: str
    parent: str
    child: str
    T_parent_child: FloatArray
    line: int | None = None

    @property
    def movable(self) -> bool:
        """True for joints that move (their zero position is used)."""
        return self.type in MOVABLE_JOINTS


@dataclass(frozen=True)
class SkippedInclude:
    """An include that names nothing reachable here, left out of the expansion.

    ``message``, ``path``, ``field`` and ``hint`` are the error it is raised as when its models could hold a
    camera that was asked for; ``cameraless`` when it names a standard model known to hold none (``model://sun``).
    """

    uri: str
    message: str
    path: str
    field: str
    hint: str
    cameraless: bool

    def error(self) -> SourceError:
        """The error this include is when it cannot be skipped."""
        return SourceError(self.message, path=self.path, field=self.field, hint=self.hint)


@dataclass
class Description:
    """A parsed robot description: links (with source lines), joints and cameras.

    ``included_files`` are the files its includes read (SDF ``<include>``), ``skipped_includes`` the includes
    that named nothing here, ``notes`` what was decided on the way (skipped includes).
    """

    path: Path
    kind: str
    links: dict[str, int | None]
    joints: list[JointSpec]
    cameras: list[CameraSpec]
    expanded_text: str = ""
    source_text: str = ""
    included_files: list[Path] = field(default_factory=list)
    skipped_includes: list[SkippedInclude] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    #: the simulator the file is written for, from the plugins it loads (:mod:`s2r.sources.simulator`)
    simulator: SimulatorGuess | None = None
    #: Where movable joints are taken, in words (MJCF: "the model's initial state" or "keyframe N"); empty means
    #: position 0 (URDF / SDF).
    joint_state: str = ""
