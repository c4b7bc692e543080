"""The one image-size rule of every recording input, and the conversion of decoded images to the frame contract.

Every decoder (image files, bag messages, video frames) checks the size the input *declares* (a PNG/JPEG header, a
bag message's width/height, a video's frame width/height) before anything is decoded: against the expected size
(the profile's camera) when one is given, and always against :data:`s2r.limits.MAX_IMAGE_PX` a side. A decoded image
whose size differs from the expected one (a format whose header s2r does not read) is refused after decoding.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.errors import RecordingError, S2RError
from s2r.limits import MAX_IMAGE_PX

__all__ = ["ExpectedSize", "SizeRule", "to_uint8"]

#: Expected (width, height) px: one size for both cameras, a (left, right) pair of sizes, or None for any.
ExpectedSize = tuple[int, int] | tuple[tuple[int, int], tuple[int, int]] | None


@dataclass(frozen=True)
class SizeRule:
    """Expected image sizes (px) of the left and right camera (None: any size up to the pixel limit) and the error
    class raised on a violation."""

    left: tuple[int, int] | None = None
    right: tuple[int, int] | None = None
    error: type[S2RError] = RecordingError

    @classmethod
    def of(cls, expected: ExpectedSize, *, error: type[S2RError] = RecordingError) -> SizeRule:
        """The rule for ``expected`` (module :data:`ExpectedSize` forms)."""
        if expected is None:
            return cls(error=error)
        if isinstance(expected[0], tuple | list):
            left, right = expected  # type: ignore[misc]
            return cls(_pair(left), _pair(right), error)
        return cls(_pair(expected), _pair(expected), error)

    def side(self, side: str) -> tuple[int, int] | None:
        """The expected size of ``side`` ('left' or 'right')."""
        return self.left if side == "left" else self.right

    def problem(self, width: int, height: int, side: str) -> str:
        """Why a ``side`` image declaring ``width`` x ``height`` px is refused ('' when it is not)."""
        if width > MAX_IMAGE_PX or height > MAX_IMAGE_PX:
            return (f"{side} image declares {width}x{height} px, larger than s2r reads ({MAX_IMAGE_PX} px a side): "
                    "a decompression bomb or a wrong file")
        want = self.side(side)
        if want is not None and (width, height) != want:
            return f"{side} image is {width}x{height} px but the profile's {side} camera is {want[0]}x{want[1]}"
        return ""

    def check(self, width: int, height: int, side: str, *, where: str, field: str | None = "image size") -> None:
        """Raise the rule's error naming ``where`` when :meth:`problem` finds one."""
        if reason := self.problem(width, height, side):
            raise self.error(reason, path=where, field=field,
                             hint="check the recording with the profile of the camera that took it")


def _pair(value: Any) -> tuple[int, int]:
    w, h = value
    return int(w), int(h)


def to_uint8(image: NDArray[Any], *, grey: bool) -> NDArray[np.uint8]:
    """A decoded image as the frame contract wants it: uint8 grey (H, W) when ``grey``, else grey (H, W) or BGR
    (H, W, 3) as recorded. 16-bit images (infrared, mono16) are scaled by 1/256, float images by their range,
    BGRA loses its alpha."""
    if image.dtype == np.uint16:
        image = (image // 256).astype(np.uint8)
    elif image.dtype != np.uint8:
        scaled = image.astype(np.float64) - float(np.nanmin(image))
        image = (255.0 * np.nan_to_num(scaled) / max(float(np.nanmax(scaled)), 1e-12)).astype(np.uint8)
    if image.ndim == 3 and image.shape[2] == 1:
        image = image[:, :, 0]
    if image.ndim == 3:
        if grey:
            image = cv2.cvtColor(image, cv2.COLOR_BGRA2GRAY if image.shape[2] == 4 else cv2.COLOR_BGR2GRAY)
        elif image.shape[2] == 4:
            image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    return np.ascontiguousarray(image, np.uint8)
