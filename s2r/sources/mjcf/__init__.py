"""MuJoCo MJCF: a ``<mujoco>`` model to a :class:`~s2r.sources.description.Description` (``reader``), from its
poses and ``<compiler>`` settings (``pose``), ``<default>`` classes (``defaults``), ``<include>`` (``include``),
``<keyframe>`` poses (``keyframe``) and cameras as MuJoCo renders them (``camera``).

Imports the description model, the include resolver and XML parsing of :mod:`s2r.sources`; the loader
(:mod:`s2r.sources.loader`) imports it. MuJoCo itself is never imported here (the parsing is s2r's own, checked
against MuJoCo in the tests).
"""

__all__: list[str] = []
