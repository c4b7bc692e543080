"""SDF: ``<sdf>`` models or a ``<world>`` to a :class:`~s2r.sources.description.Description` (``reader``), and
``<include>`` of ``model://`` and file URIs expanded as Gazebo does, in a child process (``include``).

Imports the description model, the include resolver and XML parsing of :mod:`s2r.sources`; the loader
(:mod:`s2r.sources.loader`) imports it.
"""

__all__: list[str] = []
