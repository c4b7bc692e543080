"""The figures of a validation, each computed from one or two profiles: the parameter table (``params``), the
projection difference (``projection``), Intel's depth resolution (``resolution``), the calibration recovered from
rendered boards (``recovery``) and depth accuracy on rendered ground truth (``depth_accuracy`` with its sampling
in ``depth_sampling``).

Imports ``s2r.validate.tolerances`` and the stages (render, calib, depth, lens); never the verdict, advice or run.
"""

__all__: list[str] = []
