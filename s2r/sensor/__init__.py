"""The sensor model applied: noise and blur on rendered images, a device's holes and noise on perfect depth.

The model's type lives in :mod:`s2r.sensor_model` (low in the layers, so profiles carry it); fitting it on a
recording is :mod:`s2r.sensor_fit` (above :mod:`s2r.quality`, whose board detection it uses).
"""

from s2r.sensor.depth import degrade_depth, depth_edges, nearest_fill
from s2r.sensor.files import dump_sensor_model, load_sensor_model, sensor_model_yaml
from s2r.sensor.images import blur_image, degrade_image
from s2r.sensor_model import FillPoint, SensorModel

__all__ = ["FillPoint", "SensorModel", "blur_image", "degrade_depth", "degrade_image", "depth_edges",
           "dump_sensor_model", "load_sensor_model", "nearest_fill", "sensor_model_yaml"]
