"""Intel RealSense calibrations: the ``rs-enumerate-devices -c`` text (``text``) and librealsense recordings
(``recording``: the profile of a recording's infrared pair; ``facts``: what a recording states, the model the two
layout readers fill; ``db3``: librealsense 2.56+ ROS 2 sqlite3; ``bag``: older ROS 1 bags).

Imports run one way: ``recording`` -> ``db3``, ``bag`` -> ``facts`` -> ``text`` (intrinsics) -> the shared helpers
of :mod:`s2r.formats`. :mod:`s2r.recordings` reads frames through ``recording`` and ``facts``.
"""

__all__: list[str] = []
