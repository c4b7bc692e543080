"""Camera and lens maths, one home for render, validate, quality, depth, sources and calib alike.

Layout:

- :mod:`s2r.lens.distortion` -- a profile camera's lens: points to pixels (``project_points``), OpenCV's forward
  model on normalised coordinates (``distort_normalised``), its exact inverse (``undistort_pixels``) and the rays
  of every pixel (``normalised_rays``).
- :mod:`s2r.lens.models` -- the calibration's lens models: which distortion terms a ``--distortion`` choice
  solves, and the projections with their Jacobians behind them (OpenCV pinhole, equidistant fisheye).
- :mod:`s2r.lens.fold` -- whether a solved lens model can serve its whole image (where its radial mapping folds).

Import rule: above :mod:`s2r.profile` (the :class:`~s2r.profile.Camera` type) and :mod:`s2r.errors`, below every
stage; imports nothing else of s2r (tests/test_import_graph.py). Pixel coordinates are OpenCV's (0-based, pixel
centres at integers); normalised coordinates ``(X / Z, Y / Z)`` in the camera's optical frame (z forward, x right,
y down).
"""

__all__: list[str] = []
