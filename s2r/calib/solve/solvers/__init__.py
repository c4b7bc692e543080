"""The calibration solves: OpenCV's (``cvsolve``: pinhole, ``fisheye``, ``targetcal``: corner ids), the joint
bundle adjustment of a pair (``joint`` with its residuals and Jacobians in ``jointterms``, over ``observations``),
the initial rig and its checks (``rig``) and a pair's solve from matched views (``pair``).

Imports :mod:`s2r.lens` and ``s2r.calib.solve.views``; never the honesty figures or the pipelines above it.
"""

__all__: list[str] = []
