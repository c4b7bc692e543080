"""Solve stage: from detected views to a calibrated profile with figures one can trust.

Layout (imports run one way, top to bottom imports bottom; tests/calib/test_layout.py):

- :mod:`s2r.calib.solve.pipelines` -- one module per way in: image pairs (``stereo``), bags (``stereo_bag``),
  frame streams (``stereo_stream``), one camera (``mono``), corner-id targets and fisheye lenses (``target_*``),
  and the figures each reports (``stereo_figures``, ``mono_figures``).
- :mod:`s2r.calib.solve.honesty` -- what the figures are worth: held-out errors and jackknife folds
  (``heldout``, ``resample``, ``mono_resample``, ``mono_fold``), lens-model comparison (``models``),
  projection uncertainty (``projection``), the corner-id paths' figures (``target``) and the verdict.
- :mod:`s2r.calib.solve.solvers` -- the solves themselves: OpenCV's (``cvsolve``, ``fisheye``, ``targetcal``),
  the joint bundle adjustment (``joint``, ``jointterms``, ``observations``), the rig checks (``rig``) and a
  pair's solve (``pair``).
- ``views`` (detections to views, input checks) and ``synth`` (synthetic views for tests and benchmarks).

Lens models and lens maths are :mod:`s2r.lens`. Imports :mod:`s2r.calib.detect`, never :mod:`s2r.calib.report`.
"""

__all__: list[str] = []
