"""Solve stage: lens models, mono, stereo and joint solves, uncertainties, lens-model comparison, view selection
and the verdict. Imports :mod:`s2r.calib.detect`, never :mod:`s2r.calib.report`.
"""

__all__: list[str] = []
