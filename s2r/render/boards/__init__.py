"""Calibration sets rendered through a profile: board poses that cover the image (``poses``), ChArUco and
AprilGrid targets and views cut by the image edge (``targets``), and the stereo sets with their true poses
(``sets``: :func:`~s2r.render.boards.sets.render_board_set`, also :func:`s2r.render.render_board_set`).

Imports the rig, backend, textures, world and outputs of :mod:`s2r.render`; nothing in render imports it but
``scenes`` and the package's face.
"""

__all__: list[str] = []
