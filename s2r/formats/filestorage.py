"""A safe reader for OpenCV FileStorage files (YAML and XML), returning plain Python and numpy values.

``cv2.FileStorage`` is not fit for files from strangers: a matrix without ``cols:`` makes OpenCV 5.0 corrupt
its heap (double free, exit 134/139 in some runs). This module reads the same format with PyYAML's safe
loader (:class:`s2r.safeparse.StrictSafeLoader`: duplicate keys refused) and with expat refusing any DOCTYPE (no
entity expansion), then validates every ``opencv-matrix``: ``rows``, ``cols``, ``dt`` and ``data`` present,
sizes positive and at most :data:`MAX_MATRIX_ELEMENTS`, ``len(data) == rows * cols * channels``.

Top-level node values come back as: ``str``; ``float`` (numbers); ``numpy.ndarray`` float64 (matrices as
``rows x cols`` or ``rows x cols x channels``, flat sequences of numbers as 1-D, an empty ``data: []`` placeholder
as an empty array); None for anything else
(nested maps, mixed sequences), which s2r's readers ignore.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from s2r.errors import FormatError
from s2r.fileio import read_text_file
from s2r.safeparse import StrictSafeLoader, parse_yaml, run_xml_parser, safe_xml_parser

__all__ = ["MAX_MATRIX_ELEMENTS", "NodeValue", "read_filestorage"]

NodeValue = str | float | NDArray[np.float64] | dict[str, Any]
#: Largest matrix accepted (elements): far above any calibration matrix, far below a memory problem.
MAX_MATRIX_ELEMENTS = 1_000_000
_DT = re.compile(r"^\s*([1-4]?)\s*([ucwsifdhr])\s*$")
_NARROW_FLOATS: dict[str, type[np.floating[Any]]] = {"f": np.float32, "h": np.float16}
_NO_SPACE_VALUE = re.compile(r"^(\s*[A-Za-z_][\w.]*):(?=[^\s:])")
_MATRIX_TAGS = ("tag:yaml.org,2002:opencv-matrix", "tag:yaml.org,2002:opencv-nd-matrix")


class _Matrix(dict[str, Any]):
    """An ``!!opencv-matrix`` mapping, kept apart from plain mappings until validated."""


class _FileStorageLoader(StrictSafeLoader):
    """The strict safe loader plus OpenCV's ``!!opencv-matrix`` tag (a mapping, validated afterwards)."""

    def construct_matrix(self, node: yaml.Node) -> _Matrix:
        """``!!opencv-matrix`` -> :class:`_Matrix` (the mapping's keys unchecked here)."""
        if not isinstance(node, yaml.MappingNode):
            raise yaml.constructor.ConstructorError(None, None, "opencv-matrix must be a mapping", node.start_mark)
        return _Matrix(self.construct_mapping(node, deep=True))


for _tag in _MATRIX_TAGS:
    _FileStorageLoader.add_constructor(_tag, _FileStorageLoader.construct_matrix)


def read_filestorage(path: str | Path) -> dict[str, NodeValue | None]:
    """Every top-level node of an OpenCV FileStorage file (YAML or XML, told apart by content).

    Raises:
        FormatError: unreadable, malformed, a DOCTYPE, a duplicate key, or an invalid matrix (naming the node
            and field, e.g. ``M1.cols``).
    """
    source = Path(path)
    text = read_text_file(source, error=FormatError)
    if text.lstrip().startswith("<"):
        return _read_xml(text, source)
    return _read_yaml(text, source)


def _read_yaml(text: str, path: Path) -> dict[str, NodeValue | None]:
    lines = text.splitlines()
    if lines and lines[0].startswith("%YAML"):  # OpenCV writes "%YAML:1.0" (not YAML) or "%YAML 1.2"
        lines[0] = ""
    # OpenCV's own parser accepts "data:[1, 2]" and "Viewer.PointSize:2" (no space after the colon; ORB-SLAM3's
    # EuRoC and TUM_512 settings have them), YAML does not: put the space back.
    lines = [_NO_SPACE_VALUE.sub(r"\1: ", line) for line in lines]
    try:
        data = parse_yaml("\n".join(lines), path=path, error=FormatError, loader=_FileStorageLoader)
    except FormatError as exc:
        raise FormatError(f"malformed or truncated OpenCV FileStorage: {exc.message}", path=path, field=exc.field,
                          hint="re-export the file from OpenCV") from None
    if not isinstance(data, dict):
        raise FormatError("no named nodes found (expected M1, D1, M2, D2, R, T)", path=path,
                          hint="is this an OpenCV FileStorage file?")
    return {str(key): _yaml_value(value, path, str(key)) for key, value in data.items()}


def _yaml_value(value: Any, path: Path, key: str) -> NodeValue | None:
    if isinstance(value, _Matrix):
        return _matrix(value, path, key)
    if isinstance(value, bool) or value is None:
        return None
    if isinstance(value, (int, float)):
        return _number(value)
    if isinstance(value, str):
        return value
    if isinstance(value, dict):  # a plain map (VINS distortion_parameters, Kimera's {rows, cols, data} T_BS)
        return {str(k): _yaml_value(v, path, f"{key}.{k}") for k, v in value.items()}
    if isinstance(value, list) and value and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                 for v in value):
        return np.array([_number(v) for v in value], dtype=np.float64)
    return None


_SPECIAL = {".nan": math.nan, ".inf": math.inf, "+.inf": math.inf, "-.inf": -math.inf}


def _number(value: Any) -> float:
    """A float from a number or a numeric string (OpenCV writes ``.Nan`` and ``1e5``, which YAML 1.1 reads as
    strings); ValueError when it is not one."""
    if isinstance(value, str) and value.strip().lower() in _SPECIAL:
        return _SPECIAL[value.strip().lower()]
    try:
        return float(value)
    except OverflowError:
        return math.inf  # a 400-digit integer: refused later as not finite


def _matrix(fields: dict[str, Any], path: Path, key: str) -> NDArray[np.float64]:
    """Validate an opencv-matrix's ``rows cols dt data`` and return it as float64 ``rows x cols[ x ch]``; an empty
    ``data`` (a template's placeholder, whatever its rows and cols say) as an empty array, for each reader to judge."""
    data = fields.get("data", "missing")
    if data is None or data == [] or (isinstance(data, str) and not data.strip()):
        return np.zeros((0,), dtype=np.float64)
    for name in ("rows", "cols", "dt", "data"):
        if name not in fields:
            raise FormatError("required field of an opencv-matrix is missing (malformed or truncated OpenCV "
                              "FileStorage)", path=path, field=f"{key}.{name}", hint="re-export the file from OpenCV")
    rows, cols = (_size(fields[n], path, f"{key}.{n}") for n in ("rows", "cols"))
    match = _DT.match(str(fields["dt"]).strip('"'))
    if match is None:
        raise FormatError(f"unknown element type {str(fields['dt'])[:20]!r} (expected e.g. d, f, i, u, 3d)",
                          path=path, field=f"{key}.dt")
    channels = int(match.group(1) or 1)
    expected = rows * cols * channels
    if expected > MAX_MATRIX_ELEMENTS:
        raise FormatError(f"matrix of {expected} elements is larger than {MAX_MATRIX_ELEMENTS}", path=path,
                          field=key, hint="calibration matrices are at most a few dozen numbers")
    values = _numbers(fields["data"], path, f"{key}.data")
    if len(values) != expected:
        raise FormatError(f"holds {len(values)} numbers but rows x cols x channels = {rows} x {cols} x {channels} "
                          f"= {expected}", path=path, field=f"{key}.data", hint="re-export the file from OpenCV")
    array = np.array(values, dtype=np.float64)
    if match.group(2) in _NARROW_FLOATS:  # the values the matrix holds in memory, as cv2 would return them
        with np.errstate(over="ignore"):
            array = array.astype(_NARROW_FLOATS[match.group(2)]).astype(np.float64)
    return array.reshape((rows, cols, channels) if channels > 1 else (rows, cols))


def _size(value: Any, path: Path, field: str) -> int:
    if isinstance(value, str) and value.strip().isdigit():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_MATRIX_ELEMENTS:
        raise FormatError(f"must be a whole number from 1 to {MAX_MATRIX_ELEMENTS}, got {str(value)[:20]!r}",
                          path=path, field=field)
    return value


def _numbers(value: Any, path: Path, field: str) -> list[float]:
    items = value.split() if isinstance(value, str) else value
    if not isinstance(items, list):
        raise FormatError("expected a list of numbers", path=path, field=field)
    out: list[float] = []
    for item in items:
        if isinstance(item, bool) or not isinstance(item, (int, float, str)):
            raise FormatError("expected a list of numbers", path=path, field=field)
        try:
            out.append(_number(item))  # OpenCV's "1e5" is a string to YAML 1.1, a number to OpenCV
        except ValueError:
            raise FormatError(f"not a number: {str(item)[:20]!r}", path=path, field=field) from None
    return out


def _read_xml(text: str, path: Path) -> dict[str, NodeValue | None]:
    builder = ET.TreeBuilder()
    parser = safe_xml_parser()
    parser.StartElementHandler = builder.start
    parser.EndElementHandler = builder.end
    parser.CharacterDataHandler = builder.data
    run_xml_parser(parser, text, path=path, error=FormatError)
    root = builder.close()
    if root.tag != "opencv_storage":
        raise FormatError(f"root element is <{root.tag[:40]}>, expected <opencv_storage>", path=path,
                          hint="is this an OpenCV FileStorage file?")
    nodes: dict[str, NodeValue | None] = {}
    for child in root:
        if child.tag in nodes:
            raise FormatError(f"duplicate node <{child.tag}> (each node may appear once)", path=path, field=child.tag)
        nodes[child.tag] = _xml_value(child, path)
    return nodes


def _xml_value(element: ET.Element, path: Path) -> NodeValue | None:
    if element.get("type_id") in ("opencv-matrix", "opencv-nd-matrix"):
        fields: dict[str, Any] = {}
        for sub in element:
            if sub.tag in fields:
                raise FormatError("duplicate field", path=path, field=f"{element.tag}.{sub.tag}")
            fields[sub.tag] = (sub.text or "").strip()
        return _matrix(fields, path, element.tag)
    if len(element):  # a nested map: its children by name (a sequence's unnamed "_" items are not read)
        return {child.tag: _xml_value(child, path) for child in element if child.tag != "_"}
    text = (element.text or "").strip()
    if len(text) >= 2 and text[0] == text[-1] == '"':
        return text[1:-1]
    tokens = text.split()
    try:
        numbers = [_number(t) for t in tokens]
    except ValueError:
        return text
    if not numbers:
        return None
    return numbers[0] if len(numbers) == 1 else np.array(numbers, dtype=np.float64)
