"""Robot descriptions (URDF, xacro, SDF, MuJoCo MJCF) to sim profiles, lint, and export back to Gazebo.

- :func:`load_description_profile`: a sim :class:`~s2r.profile.StereoProfile` from a description.
- :func:`lint_description`: findings about a description's stereo pair (``s2r lint``).
- :func:`export_gazebo`: Gazebo sensor XML that makes a simulated camera match a profile.

Layout (imports run one way, top imports bottom; tests/test_import_graph.py ``INNER``):

- ``profile_builder`` (read, check, build: :func:`load_description_profile`) and ``shipped``.
- :mod:`s2r.sources.lint` -- ``s2r lint``'s rules (``rules``, ``geometry``, ``mjcf``).
- ``pair_profile`` (the sim profile of a chosen pair) and :mod:`s2r.sources.export` (Gazebo and MuJoCo XML).
- ``loader`` -- reads any description and picks its stereo pair.
- One subpackage per language: :mod:`s2r.sources.urdf` (with xacro), :mod:`s2r.sources.sdf`, :mod:`s2r.sources.mjcf`.
- The description model and what every language needs: ``description``, ``sensors``, ``kinematics``,
  ``conventions`` (Gazebo's camera conventions), ``simulator``, ``includes`` (the include resolver), ``isolation``
  (untrusted work in a child process), ``xmlparse``.

Beside :mod:`s2r.formats` in the layers (neither imports the other); above profiles and :mod:`s2r.lens`.
"""

from __future__ import annotations

from s2r.sources.conventions import CONVENTIONS, gazebo_to_opencv_distortion, opencv_to_gazebo_distortion
from s2r.sources.export.gazebo import EXPORT_FORMATS, export_gazebo
from s2r.sources.lint.rules import Finding, lint_description
from s2r.sources.loader import load_description, select_pair, stereo_pair
from s2r.sources.profile_builder import load_description_profile

__all__ = [
    "CONVENTIONS",
    "EXPORT_FORMATS",
    "Finding",
    "export_gazebo",
    "gazebo_to_opencv_distortion",
    "lint_description",
    "load_description",
    "load_description_profile",
    "opencv_to_gazebo_distortion",
    "select_pair",
    "stereo_pair",
]
