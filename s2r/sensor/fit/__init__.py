"""Fitting a sensor model on a chessboard recording: image noise and blur, device depth's noise, fill and dropout.

Above :mod:`s2r.quality` (board detection, region of interest, PnP plane, recording inputs); the model's type is
:mod:`s2r.sensor.model`, applying it :mod:`s2r.sensor`.
"""

from s2r.sensor.fit.run import SensorFit, board_image, fit_device_depth, fit_images, fit_model, stereo_depth_frames

__all__ = ["SensorFit", "board_image", "fit_device_depth", "fit_images", "fit_model", "stereo_depth_frames"]
