"""Descriptions that make a simulator's camera pair match a profile: Gazebo sensor XML (``gazebo``, ``s2r profile
export-gazebo``) and MuJoCo MJCF (``mujoco``, ``s2r profile export-mujoco``).

Imports profiles, :mod:`s2r.lens` and the description model; nothing of :mod:`s2r.sources` imports it but the
package's face.
"""

__all__: list[str] = []
