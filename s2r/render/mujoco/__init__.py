"""MuJoCo as a render backend (``--renderer mujoco``): the backend itself (``backend``, the only module of s2r that
imports ``mujoco``, lazily) and the MJCF ``--world`` files s2r reads before MuJoCo sees them (``world``).

Loaded only through :mod:`s2r.render.backend` when MuJoCo is asked for; imports ``camera`` and ``world`` of
:mod:`s2r.render` for the types every backend shares.
"""

__all__: list[str] = []
