"""URDF and xacro: a URDF (after xacro expansion) to a :class:`~s2r.sources.description.Description`
(``reader``), xacro expansion through the ``xacro`` package in a child process (``xacro``), and the checked subset of
xacro's expressions a stranger's file may compute (``xacro_sandbox``, imports nothing of s2r).

Imports the description model and XML parsing of :mod:`s2r.sources` (``description``, ``sensors``, ``xmlparse``,
``isolation``); the loader (:mod:`s2r.sources.loader`) imports it, never the reverse.
"""

__all__: list[str] = []
