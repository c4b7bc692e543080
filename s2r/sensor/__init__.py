"""The sensor model: its type, applying it, and fitting it on a recording.

Layout (each part in its own layer, imports run one way, tests/test_import_graph.py):

- :mod:`s2r.sensor.model` -- the type (:class:`SensorModel`, :class:`FillPoint`). Imports nothing of s2r but
  :mod:`s2r.errors`-level modules, so :mod:`s2r.profile` can carry a model (layer of ``fileio``/``geometry``).
- :mod:`s2r.sensor.images`, :mod:`s2r.sensor.depth`, :mod:`s2r.sensor.depth_files`, :mod:`s2r.sensor.files` --
  applying it: noise and blur on rendered images, a device's holes and noise on perfect depth, the model's YAML
  file (above :mod:`s2r.formats`; render uses them).
- :mod:`s2r.sensor.fit` -- fitting it on a chessboard recording (above :mod:`s2r.quality`, whose board detection
  it uses); nothing below imports it.

The names below load their module on first use (PEP 562), so importing :mod:`s2r.sensor.model` from the profile
layer loads neither OpenCV nor the formats.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from s2r.lazy import lazy_names

if TYPE_CHECKING:
    from s2r.sensor.depth import degrade_depth, depth_edges, nearest_fill
    from s2r.sensor.files import dump_sensor_model, load_sensor_model, sensor_model_yaml
    from s2r.sensor.images import blur_image, degrade_image
    from s2r.sensor.model import FillPoint, SensorModel

#: Public name -> the module that defines it.
_HOMES = {
    "FillPoint": "s2r.sensor.model", "SensorModel": "s2r.sensor.model",
    "degrade_depth": "s2r.sensor.depth", "depth_edges": "s2r.sensor.depth", "nearest_fill": "s2r.sensor.depth",
    "dump_sensor_model": "s2r.sensor.files", "load_sensor_model": "s2r.sensor.files",
    "sensor_model_yaml": "s2r.sensor.files", "blur_image": "s2r.sensor.images", "degrade_image": "s2r.sensor.images",
}

__all__ = ["FillPoint", "SensorModel", "blur_image", "degrade_depth", "degrade_image", "depth_edges",
           "dump_sensor_model", "load_sensor_model", "nearest_fill", "sensor_model_yaml"]

__getattr__, __dir__ = lazy_names(__name__, _HOMES, globals())
