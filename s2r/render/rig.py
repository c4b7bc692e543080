"""The stereo rig of a profile in the render world, and the per-view render job run by worker processes.

World frame = the profile's LEFT optical frame. The left camera sits at the origin; the right camera's
pose follows the profile's OpenCV extrinsics, ``X_right = R X_left + T``, so ``T_right_world = [R | T]``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.errors import RenderError
from s2r.profile import SimulationSettings, StereoProfile
from s2r.render.backend import RendererChoice, get_backend
from s2r.render.sensor import CameraSetup, Capture, capture
from s2r.render.world import Surface
from s2r.sensor.images import degrade_image
from s2r.sensor.model import SensorModel

__all__ = ["MAX_RENDER_PIXELS", "StereoJob", "check_render_options", "check_render_size", "clip_planes", "finish_image",
           "render_stereo", "render_stereo_images", "stereo_setups"]

MAX_SUPERSAMPLE = 8


@functools.lru_cache(maxsize=1)
def _default_simulation() -> SimulationSettings:
    return SimulationSettings()


def clip_planes(profile: StereoProfile) -> tuple[float, float]:
    """``(near, far)`` clip planes in metres: the profile's simulation settings or the defaults."""
    sim = profile.simulation if profile.simulation is not None else _default_simulation()
    return sim.clip_near_m, sim.clip_far_m


def check_render_options(*, supersample: int, noise_sigma: float, right_gain: float = 1.0) -> None:
    """Raise RenderError naming the option when supersample, noise or gain is out of range."""
    if not 1 <= supersample <= MAX_SUPERSAMPLE:
        raise RenderError(f"supersample must be 1-{MAX_SUPERSAMPLE}, got {supersample}", field="supersample",
                          hint="2 is a good default")
    if not noise_sigma >= 0:
        raise RenderError(f"noise sigma must be >= 0 grey levels, got {noise_sigma}", field="noise_sigma",
                          hint="e.g. --noise 1.5")
    if not right_gain > 0:
        raise RenderError(f"right gain must be positive, got {right_gain}", field="right_gain", hint="1.0 = equal")


#: Most supersampled pixels one camera is rendered at (width x height x supersample^2): a render holds about
#: 85 bytes per supersampled pixel (rays, maps, the wide render, its depth; 1.5 GB for 2048x2048 at 2x), so this
#: bounds one render near 2.8 GB. 3840x2160 at 2x fits; a 16384x16384 profile (88 GB) is refused in one line.
MAX_RENDER_PIXELS = 1 << 25


def check_render_size(profile: StereoProfile, *, supersample: int) -> None:
    """Raise RenderError when a camera of ``profile`` at ``supersample`` passes :data:`MAX_RENDER_PIXELS`."""
    for side, cam in (("left", profile.left), ("right", profile.right)):
        pixels = cam.width_px * cam.height_px * supersample ** 2
        if pixels > MAX_RENDER_PIXELS:
            hint = "pass --supersample 1" if supersample > 1 and pixels // supersample ** 2 <= MAX_RENDER_PIXELS \
                else "render a smaller camera's profile"
            raise RenderError(f"rendering {cam.width_px}x{cam.height_px} px at supersample {supersample} needs about "
                              f"{pixels * 85 / 1e9:.0f} GB; s2r renders at most {MAX_RENDER_PIXELS / 1e6:.1f} million "
                              "supersampled pixels a camera", field=f"{side}.width_px", hint=hint)


def stereo_setups(profile: StereoProfile, *, supersample: int) -> tuple[CameraSetup, CameraSetup]:
    """Left and right :class:`CameraSetup` of ``profile`` (clip planes from ``profile.simulation``); RenderError
    when a camera is too large to render (:func:`check_render_size`)."""
    check_render_size(profile, supersample=supersample)
    near, far = clip_planes(profile)
    T_right_world = np.eye(4)
    T_right_world[:3, :3], T_right_world[:3, 3] = profile.R, profile.T
    return (CameraSetup(profile.left, np.eye(4), near, far, supersample),
            CameraSetup(profile.right, T_right_world, near, far, supersample))


@dataclass(frozen=True)
class StereoJob:
    """Everything a worker needs to render one stereo view (picklable)."""

    left: CameraSetup
    right: CameraSetup
    surfaces: tuple[Surface, ...]
    noise_sigma: float
    right_gain: float
    seed: int
    index: int
    renderer: RendererChoice = field(default_factory=RendererChoice)
    sensor: SensorModel | None = None


def finish_image(rgb: NDArray[np.uint8], *, gain: float, noise_sigma: float, rng: np.random.Generator,
                 sensor: SensorModel | None = None) -> NDArray[np.uint8]:
    """RGB render to the BGR uint8 image a camera delivers: gain, the sensor model's blur and image noise
    (:func:`s2r.sensor.degrade_image`), ``noise_sigma`` more image noise, rounding.

    Image noise means one thing everywhere (``render --noise``, the sensor model's ``image_noise_dn`` and
    ``sensor fit``): the sigma, in grey levels of the 8-bit range, of additive Gaussian noise in the GREY image the
    matcher and the fit read, before 8-bit rounding. It is drawn as one plane shared by the colour channels, so the
    grey conversion (weights summing to 1) carries it whole; ``noise_sigma`` and the model's noise are independent
    and add in variance. Every renderer's images pass through here, so this applies to every backend alike."""
    bgr = (np.asarray(cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2BGR), np.uint8)  # 5x numpy's [..., ::-1]
           if rgb.ndim == 3 and rgb.shape[2] == 3 else np.ascontiguousarray(rgb[:, :, ::-1]))
    if gain == 1.0 and noise_sigma == 0.0 and sensor is None:
        return bgr
    out = degrade_image(bgr.astype(np.float32) * np.float32(gain), sensor, rng)
    if noise_sigma > 0:
        plane = rng.normal(0.0, noise_sigma, size=out.shape[:2]).astype(np.float32)
        out += plane[:, :, None] if out.ndim == 3 else plane
    return np.asarray(np.clip(np.round(out), 0, 255), dtype=np.uint8)


def render_stereo(job: StereoJob) -> tuple[Capture, Capture]:
    """Set the job's renderer's world to its surfaces and capture both cameras (in this process)."""
    backend = get_backend(job.renderer)
    backend.set_world(job.surfaces)
    return capture(job.left, backend), capture(job.right, backend)


def render_stereo_images(job: StereoJob) -> tuple[NDArray[np.uint8], NDArray[np.uint8]]:
    """The job's left and right BGR uint8 images (noise seeded by ``(seed, index)``)."""
    left, right = render_stereo(job)
    rng = np.random.default_rng([job.seed, job.index])
    return (finish_image(left.rgb, gain=1.0, noise_sigma=job.noise_sigma, rng=rng, sensor=job.sensor),
            finish_image(right.rgb, gain=job.right_gain, noise_sigma=job.noise_sigma, rng=rng, sensor=job.sensor))
