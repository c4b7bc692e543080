"""What to change when a validation fails: concrete edits to a Gazebo description (``edits``) or a MuJoCo
``<camera>`` (``mujoco``), and the root causes that group the failing checks by the one sim parameter explaining
them (``causes``).

Imports the measures and ``verdict`` below it; imported by ``run`` and ``summary``.
"""

__all__: list[str] = []
