"""A sensor model on rendered images: Gaussian optics blur, then grey-level Gaussian noise (before rounding).

Applied to every rendered stereo image in one place (:func:`s2r.render.rig.finish_image`), after the renderer
has produced the image and before it is rounded to 8 bits, so every renderer backend gets the same sensor.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.sensor.model import SensorModel

__all__ = ["blur_image", "degrade_image", "gaussian_blur"]


def gaussian_blur(image: NDArray[np.float32], sigma_px: float) -> NDArray[np.float32]:
    """``image`` (H, W) or (H, W, C) float32 convolved with a Gaussian of ``sigma_px`` pixels (reflected borders;
    the kernel spans +-4 sigma)."""
    if sigma_px <= 0:
        return image
    size = 2 * math.ceil(4.0 * sigma_px) + 1
    return np.asarray(cv2.GaussianBlur(image, (size, size), sigmaX=sigma_px, sigmaY=sigma_px,
                                       borderType=cv2.BORDER_REFLECT), dtype=np.float32)


def blur_image(image: NDArray[np.float32], model: SensorModel | None) -> NDArray[np.float32]:
    """The model's optics blur on a float32 image (unchanged without a model or a blur figure)."""
    if model is None or not model.blur_sigma_px:
        return image
    return gaussian_blur(image, model.blur_sigma_px)


def degrade_image(image: NDArray[np.float32], model: SensorModel | None, rng: np.random.Generator
                  ) -> NDArray[np.float32]:
    """Blur, then add the model's grey-level noise (one noise plane shared by every channel, as a monochrome
    sensor's); float32 grey levels in, float32 out (the caller rounds and clips to 8 bits)."""
    out = blur_image(np.asarray(image, np.float32), model)
    if model is not None and model.image_noise_dn:
        noise = rng.normal(0.0, model.image_noise_dn, size=out.shape[:2]).astype(np.float32)
        out = out + (noise[:, :, None] if out.ndim == 3 else noise)
    return out
