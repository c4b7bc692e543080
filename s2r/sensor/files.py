"""Sensor model files: ``sensor.yaml`` (the model alone) or a profile's ``sensor:`` section."""

from __future__ import annotations

from pathlib import Path

import yaml

from s2r.errors import ProfileError
from s2r.fileio import atomic_write_text
from s2r.formats.s2r_yaml import profile_from_mapping, read_yaml_mapping
from s2r.sensor.model import SensorModel

__all__ = ["dump_sensor_model", "load_sensor_model", "sensor_model_yaml"]

_HEADER = (
    "# s2r sensor model (schema_version 1): image noise in 8-bit grey levels, blur and disparity noise in pixels,\n"
    "# fill rate in % of a surface's pixels against its distance in metres (see s2r.sensor.model).\n"
)


def load_sensor_model(path: str | Path) -> SensorModel:
    """A sensor model from ``sensor.yaml`` or from a profile YAML's ``sensor:`` section; ProfileError naming the
    file and field when it is neither."""
    data = read_yaml_mapping(path)
    if "left" in data and "extrinsics" in data:  # a whole profile: its sensor section
        section = data.get("sensor")
        if not isinstance(section, dict):
            raise ProfileError("this profile has no sensor: section", path=path, field="sensor",
                               hint="fit one with s2r sensor fit, or pass a sensor.yaml")
        data = section
    model = profile_from_mapping(data, SensorModel, path=path)
    return model


def sensor_model_yaml(model: SensorModel) -> str:
    """The model as YAML text (None fields left out), with a header comment giving the units."""
    return _HEADER + yaml.safe_dump(model.model_dump(mode="json", exclude_none=True), sort_keys=False, width=110)


def dump_sensor_model(model: SensorModel, path: str | Path, *, force: bool = False) -> Path:
    """Write ``model`` to ``path`` atomically; refuse to overwrite unless ``force``."""
    return atomic_write_text(path, sensor_model_yaml(model), force=force)
