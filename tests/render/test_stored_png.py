"""Temporary PNGs stored without compression (textures, validate's board set): the same pixels, read back by
OpenCV and by PyBullet's texture loader; a persisted set keeps OpenCV's compressed default."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from s2r.render._pybullet import p
from s2r.render.camera import client
from s2r.render.outputs import STORED_PNG, encode_png
from s2r.render.rig import finish_image
from s2r.render.textures import speckle_texture, write_png


def test_stored_png_is_lossless_and_uncompressed(tmp_path: Path) -> None:
    rgb = speckle_texture(256, seed=5)
    bgr = np.ascontiguousarray(rgb[:, :, ::-1])
    stored = encode_png(tmp_path / "stored.png", bgr, stored=True)
    packed = encode_png(tmp_path / "packed.png", bgr)
    for path in (stored, packed):
        assert np.array_equal(cv2.imread(str(path), cv2.IMREAD_COLOR), bgr)
        assert np.array_equal(cv2.imread(str(path), cv2.IMREAD_GRAYSCALE),
                              cv2.imread(str(packed), cv2.IMREAD_GRAYSCALE))
    assert stored.stat().st_size > bgr.size  # raw bytes plus per-row filter bytes: nothing compressed
    assert packed.stat().st_size < stored.stat().st_size
    assert STORED_PNG[:2] == (cv2.IMWRITE_PNG_COMPRESSION, 0)


def test_stored_texture_loads_in_pybullet(tmp_path: Path) -> None:
    rgb = speckle_texture(128, seed=2)
    path = write_png(tmp_path / "tex.png", rgb)
    assert np.array_equal(cv2.imread(path)[:, :, ::-1], rgb)
    assert p.loadTexture(path, physicsClientId=client()) >= 0


def test_finish_image_swaps_channels_exactly() -> None:
    rgb = np.random.default_rng(0).integers(0, 256, (31, 47, 3), dtype=np.uint8)
    out = finish_image(rgb, gain=1.0, noise_sigma=0.0, rng=np.random.default_rng(1))
    assert out.flags["C_CONTIGUOUS"] and out.dtype == np.uint8
    assert np.array_equal(out, rgb[:, :, ::-1])
