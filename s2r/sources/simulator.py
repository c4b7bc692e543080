"""Which simulator a description is written for, from what it loads: the pixel convention to use, and whose advice.

Gazebo classic and gz-sim publish different principal points for the same ``horizontal_fov``
(:mod:`s2r.sources.conventions`): reading a gz-sim world with classic's convention is 0.5 px off. The file usually
says which simulator it is for:

- **gz-sim**: a ``<plugin>`` whose ``filename`` is a gz-sim (or Ignition Gazebo) system (``gz-sim-sensors-system``,
  ``libgz-sim-...``, ``ignition-gazebo-...``, ``gz_ros2_control``) or whose ``name`` is in ``gz::sim::`` /
  ``ignition::gazebo::``; a ``<render_engine>`` (gz-sim's sensors system: ``ogre2``); a camera's
  ``<optical_frame_id>`` / ``<gz_frame_id>`` / ``<ignition_frame_id>`` (gz-sensors only).
- **Gazebo classic**: a gazebo_ros plugin (``libgazebo_ros_camera.so``, ``libgazebo_ros_multicamera.so``, ...).

Evidence for one only decides; evidence for both, or for neither, decides nothing (the caller falls back to its
default and says so).
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from s2r.sources.includes import shown
from s2r.sources.xmlparse import XmlDoc

__all__ = ["SIMULATORS", "SimulatorGuess", "infer_simulator"]

SIMULATORS = ("gazebo-classic", "gz-sim")
_GZ_FILE = re.compile(r"^(lib)?(gz-sim|gz_sim|ignition-gazebo|ign-gazebo|gz_ros2_control|ign_ros2_control)", re.I)
_GZ_NAME = re.compile(r"^(gz|ignition)::(sim|gazebo)::", re.I)
_CLASSIC_FILE = re.compile(r"^(lib)?gazebo_ros_", re.I)
_GZ_TAGS = ("render_engine", "optical_frame_id", "gz_frame_id", "ignition_frame_id")


@dataclass(frozen=True)
class SimulatorGuess:
    """The simulator a description is written for (None: no evidence, or evidence for both) and why.

    Attributes:
        simulator: ``gazebo-classic``, ``gz-sim`` or None.
        evidence: the first element that decided (``<plugin filename='gz-sim-sensors-system'> line 7``), or for
            an undecided guess what was found for each (empty when nothing was).
    """

    simulator: str | None
    evidence: str = ""


def _where(doc: XmlDoc, element: ET.Element, label: str, lines: bool) -> str:
    line = doc.line(element) if lines else None
    return label + (f" line {line}" if line else "")


def _evidence(doc: XmlDoc, lines: bool) -> dict[str, list[str]]:
    found: dict[str, list[str]] = {name: [] for name in SIMULATORS}
    for element in doc.root.iter():
        tag = element.tag if isinstance(element.tag, str) else ""
        if tag == "plugin":
            filename, name = element.get("filename", "").strip(), element.get("name", "").strip()
            label = f"<plugin filename={filename!r}>"
            if _GZ_FILE.match(filename) or _GZ_NAME.match(name):
                found["gz-sim"].append(_where(doc, element, label, lines))
            elif _CLASSIC_FILE.match(filename):
                found["gazebo-classic"].append(_where(doc, element, label, lines))
        elif tag in _GZ_TAGS:
            text = shown((element.text or "").strip(), 40)
            found["gz-sim"].append(_where(doc, element, f"<{tag}>{text}</{tag}>", lines))
    return found


def infer_simulator(doc: XmlDoc, *, lines: bool = True) -> SimulatorGuess:
    """The simulator ``doc`` (an expanded URDF or SDF) loads plugins or elements of (module docstring).

    ``lines``: name the evidence's line (False for xacro, whose expanded lines are not the file's)."""
    found = _evidence(doc, lines)
    gz, classic = found["gz-sim"], found["gazebo-classic"]
    if gz and not classic:
        return SimulatorGuess("gz-sim", gz[0])
    if classic and not gz:
        return SimulatorGuess("gazebo-classic", classic[0])
    if gz and classic:
        return SimulatorGuess(None, f"gz-sim ({gz[0]}) and Gazebo classic ({classic[0]})")
    return SimulatorGuess(None)
