"""Stereo frames from still image files: a calibrate-style folder or two globs (:mod:`s2r.recordings.pairing`),
decoded one pair at a time through s2r's bounded image reader, each header's size checked before decoding."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.errors import CalibrationError
from s2r.imageio import decode_image_file
from s2r.recordings.decode import SizeRule, to_uint8
from s2r.recordings.frames import StereoFrame, thinned
from s2r.recordings.pairing import PairSet, find_stereo_pairs

__all__ = ["FileFrames", "decode_side"]


def decode_side(path: Path, rule: SizeRule, side: str, *, grey: bool) -> NDArray[np.uint8]:
    """The image file ``path`` as a ``side`` frame image: refused (``rule.error``) when unreadable, when its header
    declares a size other than the expected one (before decoding) or when the decoded size differs."""
    image, reason = decode_image_file(path, cv2.IMREAD_GRAYSCALE if grey else cv2.IMREAD_UNCHANGED,
                                      expected_size=rule.side(side))
    if image is None:
        size = reason.startswith("the header declares")  # oversize or not the expected size: refused undecoded
        raise rule.error(f"{side} image: {reason}", path=path, field="image size" if size else None,
                         hint="check the recording with the profile of the camera that took it" if size else
                         "pass readable image files")
    rule.check(int(image.shape[1]), int(image.shape[0]), side, where=str(path))
    return to_uint8(image, grey=grey)


@dataclass
class FileFrames:
    """A folder (calibrate's layouts) or ``left_glob`` + ``right_glob``, as a :class:`FrameSource`.

    ``every`` keeps every N-th pair, ``max_frames`` stops after that many kept pairs (None: all).
    """

    folder: Path | None = None
    left_glob: str | None = None
    right_glob: str | None = None
    rule: SizeRule = field(default_factory=SizeRule)
    grey: bool = False
    every: int = 1
    max_frames: int | None = None
    #: Positions (after ``every`` / ``max_frames``) to decode, in order; None: all of them.
    indices: tuple[int, ...] | None = None

    def __post_init__(self) -> None:
        self.pairs = self._find()

    def _find(self) -> PairSet:
        try:
            pairs = find_stereo_pairs(self.folder, left_glob=self.left_glob, right_glob=self.right_glob)
        except CalibrationError as exc:  # the finder's message names the folder or glob
            if self.rule.error is CalibrationError:
                raise
            raise self.rule.error(exc.message, path=exc.path, field=exc.field, hint=exc.hint) from None
        if not pairs.names:
            unpaired = f"; unpaired: {', '.join(p.name for p in pairs.unpaired[:3])}" if pairs.unpaired else ""
            raise self.rule.error(f"no left/right image pairs found{unpaired}", path=self.describe(),
                                  hint="give each left image a right partner with the same number")
        return pairs

    @property
    def skipped(self) -> list[str]:
        """Image files without a partner (skipped), as found when this source was made."""
        return [str(p) for p in self.pairs.unpaired]

    def __len__(self) -> int:
        """Pairs this source yields (after ``every`` and ``max_frames``)."""
        n = len(range(0, len(self.pairs.names), self.every))
        return n if self.max_frames is None else min(n, self.max_frames)

    def describe(self) -> str:
        """The folder or the two globs."""
        if self.folder is not None and self.left_glob is None:
            return str(self.folder)
        return f"{self.left_glob} + {self.right_glob}"

    def frames(self) -> Iterator[StereoFrame]:
        """Decoded pairs in pairing order (by the number in the names), one at a time."""
        positions = [k for k, _ in thinned(range(len(self.pairs.names)), self.every, self.max_frames)]
        for k in positions if self.indices is None else [positions[i] for i in self.indices]:
            lp, rp = self.pairs.left[k], self.pairs.right[k]
            yield StereoFrame(index=k, name=self.pairs.names[k], stamp_ns=None, frame_id="",
                              left=decode_side(lp, self.rule, "left", grey=self.grey),
                              right=decode_side(rp, self.rule, "right", grey=self.grey),
                              source=f"{lp} + {rp}")
