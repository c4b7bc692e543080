"""The calibration pipelines, one per way in: image pairs (``stereo``), ROS bags (``stereo_bag``), frame streams
(``stereo_stream``), one camera (``mono``), corner-id targets and fisheye lenses (``target_stereo``,
``target_mono``, ``target_joint``), and the figures each reports (``stereo_figures``, ``mono_figures``).

The top of the solve stage: imports the solvers and the honesty figures below it; the public names are
:mod:`s2r.calib`'s.
"""

__all__: list[str] = []
