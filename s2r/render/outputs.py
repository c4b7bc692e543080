"""Writing rendered sets: numbered file names, PNG/NPY through atomic writes, safe reuse of a folder."""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.errors import RenderError
from s2r.fileio import atomic_write_bytes, check_output_dir, prepare_output_dir

__all__ = ["check_output_dir", "clear_numbered", "encode_png", "numbered_names"]

_NUMBERED = re.compile(r"^\d+\.(png|npy)$")


def numbered_names(count: int) -> list[str]:
    """``["00", "01", ...]``: zero-padded to at least two digits, enough for ``count`` items."""
    width = max(2, len(str(max(count - 1, 0))))
    return [f"{k:0{width}d}" for k in range(count)]


def clear_numbered(out_dir: str | Path, subdirs: Sequence[str], *, force: bool) -> Path:
    """Prepare ``out_dir`` (refused if it holds files unless ``force``) and its ``subdirs``.

    With ``force``, numbered files (``NN.png`` / ``NN.npy``) already in the subfolders are removed so a
    smaller set does not leave stale views behind; nothing else is touched.
    """
    out = prepare_output_dir(out_dir, force=force)
    for name in subdirs:
        sub = out / name
        if sub.exists() and not sub.is_dir():
            raise RenderError("exists and is not a folder", path=sub, hint="choose another output folder")
        sub.mkdir(exist_ok=True)
        for old in sub.iterdir():
            if old.is_file() and _NUMBERED.match(old.name):
                old.unlink()
    return out


def encode_png(path: Path, bgr: NDArray[np.uint8]) -> Path:
    """Write a BGR (or grey) uint8 image as PNG, atomically."""
    ok, buf = cv2.imencode(".png", bgr)
    if not ok:
        raise RenderError("cannot encode PNG", path=path)
    return atomic_write_bytes(path, buf.tobytes(), force=True)
