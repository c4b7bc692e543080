"""Calibration targets described in a file: Kalibr AprilGrids and checkerboards, OpenCV ChArUco boards.

A TARGET.yaml is either Kalibr's own target file (``target_type: 'aprilgrid'`` or ``'checkerboard'``, with
Kalibr's field names) or a ChArUco board with ``cv2.aruco.CharucoBoard``'s argument names
(``target_type: charuco``). Each target knows the board-frame position (metres, z = 0) of every corner id:

- checkerboard: id ``r * targetCols + c`` for the inner corner in row r, column c (OpenCV's row-major
  order), at ``(c * colSpacingMeters, r * rowSpacingMeters, 0)``;
- charuco: OpenCV's ChArUco corner ids (``(squaresX - 1) * (squaresY - 1)`` inner corners, row-major from the
  top left), at ``((c + 1) * squareLength, (r + 1) * squareLength, 0)`` (OpenCV's board frame: origin at
  the board's top-left outer corner, x right, y down);
- aprilgrid: Kalibr's point ids on the ``2 tagCols x 2 tagRows`` grid of tag corners, id ``r * 2 tagCols + c``
  at ``((c // 2) (1 + tagSpacing) tagSize + (c % 2) tagSize, (r // 2) (1 + tagSpacing) tagSize
  + (r % 2) tagSize, 0)`` (Kalibr's frame: origin at tag 0's bottom-left corner, x right, y up); tag ``t``'s
  corners (bottom-left, bottom-right, top-right, top-left) are ids ``b, b + 1, b + 2 tagCols + 1,
  b + 2 tagCols`` with ``b = (t // tagCols) 4 tagCols + (t % tagCols) 2``.

cv2-free: the detectors (:mod:`s2r.calib.detect.markers`) and the renderer build OpenCV objects from these fields.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, TypeAdapter, ValidationError, model_validator

from s2r.errors import CalibrationError
from s2r.fileio import read_text_file
from s2r.limits import MAX_SQUARE_M
from s2r.safeparse import parse_yaml

__all__ = [
    "ARUCO_DICTIONARIES",
    "DETECTOR_REVISION",
    "MAX_SQUARE_M",
    "AnyTarget",
    "AprilGridTarget",
    "CharucoTarget",
    "CheckerboardTarget",
    "Target",
    "load_target",
    "target_from_mapping",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.integer[Any]]

#: Revision of the corner detectors of file-described targets (s2r.calib.detect.markers), part of the corner cache's
#: key: bumped when their output changes, so cached detections of an older detector are not reused.
DETECTOR_REVISION = 2

#: OpenCV's predefined ArUco / AprilTag dictionaries (cv2.aruco.DICT_*), by name.
ARUCO_DICTIONARIES: tuple[str, ...] = (
    *(f"DICT_{b}X{b}_{n}" for b in (4, 5, 6, 7) for n in (50, 100, 250, 1000)),
    "DICT_ARUCO_ORIGINAL", "DICT_APRILTAG_16h5", "DICT_APRILTAG_25h9", "DICT_APRILTAG_36h10",
    "DICT_APRILTAG_36h11", "DICT_ARUCO_MIP_36h12",
)
_DICT_SIZE = {name: int(name.rsplit("_", 1)[1]) for name in ARUCO_DICTIONARIES if name[5].isdigit()}
_DICT_SIZE.update({"DICT_ARUCO_ORIGINAL": 1024, "DICT_APRILTAG_16h5": 30, "DICT_APRILTAG_25h9": 35,
                   "DICT_APRILTAG_36h10": 2320, "DICT_APRILTAG_36h11": 587, "DICT_ARUCO_MIP_36h12": 250})


class _Target(BaseModel):
    # Kalibr's own files carry extra keys some tools add (comments become keys in hand-edited files are
    # rare); unknown keys are refused so a misspelt field is named rather than ignored.
    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    @property
    def corner_count(self) -> int:
        """Number of corner ids of the board."""
        return len(self.object_points())

    def object_points(self) -> FloatArray:
        """Board-frame positions (N, 3) in metres of corner ids ``0..N-1``."""
        raise NotImplementedError

    def points_of(self, ids: IntArray) -> FloatArray:
        """Board-frame positions (len(ids), 3) in metres of the given corner ids."""
        pts = self.object_points()
        ids = np.asarray(ids, np.int64).reshape(-1)
        if ids.size and (ids.min() < 0 or ids.max() >= len(pts)):
            raise CalibrationError(f"corner id {int(ids.max())} is not on the target ({len(pts)} corners)")
        return pts[ids]

    def describe(self) -> str:
        """A short human description, e.g. ``aprilgrid 6x6 tags of 88 mm``."""
        raise NotImplementedError


class CheckerboardTarget(_Target):
    """Kalibr's checkerboard: inner corners ``targetCols`` x ``targetRows``, spacings in metres."""

    target_type: Literal["checkerboard"]
    targetCols: int = Field(ge=2, le=200)
    targetRows: int = Field(ge=2, le=200)
    rowSpacingMeters: float = Field(gt=0, le=10)
    colSpacingMeters: float = Field(gt=0, le=10)

    @property
    def pattern(self) -> tuple[int, int]:
        """Inner corners ``(cols, rows)`` as OpenCV's chessboard detector wants them."""
        return (self.targetCols, self.targetRows)

    def object_points(self) -> FloatArray:
        r, c = np.divmod(np.arange(self.targetCols * self.targetRows), self.targetCols)
        return np.column_stack([c * self.colSpacingMeters, r * self.rowSpacingMeters, np.zeros(r.size)])

    def describe(self) -> str:
        return (f"checkerboard {self.targetCols}x{self.targetRows} inner corners, "
                f"{self.colSpacingMeters * 1000:g}x{self.rowSpacingMeters * 1000:g} mm")


class CharucoTarget(_Target):
    """A ChArUco board with ``cv2.aruco.CharucoBoard``'s argument names (lengths in metres)."""

    target_type: Literal["charuco"]
    squaresX: int = Field(ge=2, le=200)
    squaresY: int = Field(ge=2, le=200)
    squareLength: float = Field(gt=0, le=10)
    markerLength: float = Field(gt=0, le=10)
    dictionary: str
    legacyPattern: bool = False

    @model_validator(mode="after")
    def _consistent(self) -> CharucoTarget:
        if self.dictionary not in ARUCO_DICTIONARIES:
            raise ValueError(f"dictionary: unknown OpenCV dictionary {self.dictionary!r}; use one of "
                             "DICT_4X4_50 .. DICT_7X7_1000, DICT_ARUCO_ORIGINAL, DICT_APRILTAG_36h11, ...")
        if self.markerLength >= self.squareLength:
            raise ValueError(f"markerLength: {self.markerLength} m must be smaller than squareLength "
                             f"{self.squareLength} m (the marker sits inside a white square)")
        markers = (self.squaresX * self.squaresY) // 2
        if markers > _DICT_SIZE[self.dictionary]:
            raise ValueError(f"dictionary: {self.dictionary} has {_DICT_SIZE[self.dictionary]} markers but a "
                             f"{self.squaresX}x{self.squaresY} board needs {markers}; use a larger dictionary")
        return self

    def object_points(self) -> FloatArray:
        r, c = np.divmod(np.arange((self.squaresX - 1) * (self.squaresY - 1)), self.squaresX - 1)
        return np.column_stack([(c + 1) * self.squareLength, (r + 1) * self.squareLength, np.zeros(r.size)])

    def describe(self) -> str:
        return (f"charuco {self.squaresX}x{self.squaresY} squares of {self.squareLength * 1000:g} mm, "
                f"{self.dictionary}")


class AprilGridTarget(_Target):
    """Kalibr's AprilGrid: tag36h11 tags (2-bit border), ``tagSize`` black edge to edge (m), ``tagSpacing``
    the gap as a fraction of ``tagSize``; tag 0 at the bottom left."""

    target_type: Literal["aprilgrid"]
    tagCols: int = Field(ge=1, le=100)
    tagRows: int = Field(ge=1, le=100)
    tagSize: float = Field(gt=0, le=10)
    tagSpacing: float = Field(gt=0, le=2)
    codeOffset: int = Field(default=0, ge=0)

    @model_validator(mode="after")
    def _fits_dictionary(self) -> AprilGridTarget:
        if self.codeOffset + self.tagCols * self.tagRows > _DICT_SIZE["DICT_APRILTAG_36h11"]:
            raise ValueError(f"tagCols: {self.tagCols}x{self.tagRows} tags exceed tag36h11's 587 codes")
        return self

    @property
    def tag_count(self) -> int:
        """Number of tags."""
        return self.tagCols * self.tagRows

    def object_points(self) -> FloatArray:
        cols = 2 * self.tagCols
        r, c = np.divmod(np.arange(cols * 2 * self.tagRows), cols)
        pitch = (1.0 + self.tagSpacing) * self.tagSize
        return np.column_stack([(c // 2) * pitch + (c % 2) * self.tagSize, (r // 2) * pitch + (r % 2) * self.tagSize,
                                np.zeros(r.size)])

    def tag_corner_ids(self, tag_ids: IntArray) -> IntArray:
        """Corner ids (len(tag_ids), 4) of tags: bottom-left, bottom-right, top-right, top-left (Kalibr)."""
        t = np.asarray(tag_ids, np.int64).reshape(-1) - self.codeOffset
        cols = 2 * self.tagCols
        base = (t // self.tagCols) * 2 * cols + (t % self.tagCols) * 2
        return np.column_stack([base, base + 1, base + cols + 1, base + cols])

    def describe(self) -> str:
        return f"aprilgrid {self.tagCols}x{self.tagRows} tags of {self.tagSize * 1000:g} mm"


#: Any target a file can describe (the type every detector, solver and renderer takes).
AnyTarget = CheckerboardTarget | CharucoTarget | AprilGridTarget
Target = Annotated[AnyTarget, Field(discriminator="target_type")]
_ADAPTER: TypeAdapter[AnyTarget] = TypeAdapter(Target)


def _message(exc: ValidationError) -> tuple[str, str]:
    err = exc.errors()[0]
    loc = [str(p) for p in err["loc"] if str(p) not in ("checkerboard", "charuco", "aprilgrid")]
    msg = str(err["msg"]).removeprefix("Value error, ")
    if ":" in msg.split(" ")[0]:  # "field: message" from the validators above
        name, msg = msg.split(":", 1)
        loc = [name]
    if err["type"] == "extra_forbidden":
        msg = "unknown field (remove it or check its spelling)"
    elif err["type"] == "missing":
        msg = "required field is missing (add it)"
    elif err["type"] == "union_tag_invalid":
        loc, msg = ["target_type"], "must be 'aprilgrid', 'checkerboard' or 'charuco'"
    elif err["type"] == "union_tag_not_found":
        loc, msg = ["target_type"], "missing: add target_type: aprilgrid | checkerboard | charuco"
    return ".".join(loc) or "(top level)", msg.strip()


def target_from_mapping(data: Any, *, path: str | Path | None = None
                        ) -> AnyTarget:
    """Validate a parsed target mapping; CalibrationError naming the file and the field otherwise."""
    if not isinstance(data, dict):
        raise CalibrationError("expected a YAML mapping (target_type: ..., ...)", path=path,
                               hint="see Kalibr's target files or s2r's README for the fields")
    data = {str(k): (v.strip("'\"") if isinstance(v, str) else v) for k, v in data.items()}
    try:
        return _ADAPTER.validate_python(data)
    except ValidationError as exc:
        field, msg = _message(exc)
        raise CalibrationError(msg, path=path, field=field, hint="fix the target file") from None


def load_target(path: str | Path) -> AnyTarget:
    """Read a TARGET.yaml (Kalibr aprilgrid / checkerboard, or charuco); one-line errors naming the field."""
    source = Path(path)
    text = read_text_file(source, error=CalibrationError)
    return target_from_mapping(parse_yaml(text, path=source, error=CalibrationError), path=source)
