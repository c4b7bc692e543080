"""Independent image-based known-answer stereo rigs: chessboard images ray-cast through random plumb_bob lenses.

Built on tests/raycast.py (a numpy ray caster sharing no code with s2r: its own plumb_bob projection and
inversion, an anti-aliased 3x3 supersampled chessboard texture, seeded sensor noise), used read-only. This
module adds random lenses like the ones the issue's hidden rigs describe and a pose sampler that keeps the
whole printed board (inner corners, outer squares and a white quiet zone) inside both images, so that every
view is a fair test of chessboard corner detection rather than of partial-board handling.

A rig: two cameras (640x480 or 1280x720) with random plumb_bob lenses (f 450-650 px at 640x480, scaled with
the width; |p1|, |p2| <= 5e-4; |k3| <= 0.02), the right camera's centre 6-12 cm to the right of the left one
(``X_right = R X_left + T``, metres, OpenCV optical frames: x right, y down, z forward), rotated up to about
1.5 degrees; a 9x6 chessboard with 25 mm squares in ``views`` poses tilted 10-45 degrees (sampled here); each image is
blurred by a Gaussian of sigma 0.3-0.7 px after sensor noise of 1-2 grey levels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from tests import raycast as rc

Array = NDArray[np.float64]
PATTERN = (9, 6)
SQUARE_M = 0.025


@dataclass(frozen=True)
class ImageRig:
    """Truth of a rendered rig: lenses (fx fy cx cy px, dist k1 k2 p1 p2 k3), ``X_right = R X_left + T``,
    and (after rendering) the true pixel positions (54, 2) of the inner corners per view, left and right,
    in OpenCV's row-major order from the board's top-left inner corner."""

    left: rc.Lens
    right: rc.Lens
    R: Array
    T: Array
    size: tuple[int, int]
    corners: tuple[tuple[Array, Array], ...] = ()

    @property
    def baseline_m(self) -> float:
        return float(np.linalg.norm(self.T))


def _lens(rng: np.random.Generator, size: tuple[int, int]) -> rc.Lens:
    w, h = size
    s = w / 640.0
    fx = rng.uniform(450, 650) * s
    fy = fx * (1 + rng.uniform(-0.003, 0.003))
    dist = (rng.uniform(-0.25, 0.05), rng.uniform(-0.05, 0.12), rng.uniform(-5e-4, 5e-4), rng.uniform(-5e-4, 5e-4),
            rng.uniform(-0.02, 0.02))
    return rc.Lens(w, h, fx, fy, (w - 1) / 2 + rng.uniform(-12, 12) * s, (h - 1) / 2 + rng.uniform(-10, 10) * s,
                   "plumb_bob", dist)


def make_image_rig(seed: int, size: tuple[int, int] = (640, 480)) -> tuple[ImageRig, rc.Rig]:
    """A random rig (its truth and the ray caster's rig with a 9x6, 25 mm chessboard)."""
    rng = np.random.default_rng(seed)
    left, right = _lens(rng, size), _lens(rng, size)
    R = np.asarray(cv2.Rodrigues(np.radians(rng.uniform(-1.5, 1.5, 3)).reshape(3, 1))[0], np.float64)
    centre = np.array([rng.uniform(0.06, 0.12), rng.uniform(-0.002, 0.002), rng.uniform(-0.002, 0.002)])
    T = -R @ centre
    target = rc.chessboard_target(PATTERN, SQUARE_M, tpx=64)
    return ImageRig(left, right, R, T, size), rc.Rig(f"rig{seed}", left, right, R, T, target)


def _poses(rig: rc.Rig, views: int, seed: int) -> list[tuple[Array, Array]]:
    """Board poses (R_left_board, t_left_board): the board fills 35-80 % of the image width, centred anywhere
    in the middle 70 % of the image, tilted 10-45 degrees about a random axis and rolled up to 30 degrees;
    the board with half a square of its white quiet zone lies wholly inside both images (2 px margin)."""
    rng = np.random.default_rng(seed)
    x0, y0, x1, y1 = rig.target.extent
    m = 0.5 * SQUARE_M  # of the one-square quiet zone, keep half in view
    a0, b0, a1, b1 = x0 + m, y0 + m, x1 - m, y1 - m
    edge = np.linspace(0, 1, 9)
    outline = np.concatenate([np.column_stack([a0 + (a1 - a0) * edge, np.full(9, b0)]),
                              np.column_stack([a0 + (a1 - a0) * edge, np.full(9, b1)]),
                              np.column_stack([np.full(9, a0), b0 + (b1 - b0) * edge]),
                              np.column_stack([np.full(9, a1), b0 + (b1 - b0) * edge])])
    outline = np.column_stack([outline, np.zeros(len(outline))])
    centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2, 0.0])
    lens = rig.left
    out: list[tuple[Array, Array]] = []
    for _ in range(200 * views):
        if len(out) == views:
            return out
        share = rng.uniform(0.35, 0.8)
        dist = (a1 - a0) * lens.fx / (share * lens.width)
        u = lens.cx + rng.uniform(-0.35, 0.35) * lens.width
        v = lens.cy + rng.uniform(-0.35, 0.35) * lens.height
        ray = lens.rays(np.array([u]), np.array([v]))[0]
        axis = rng.uniform(0, 2 * math.pi)
        tilt = math.radians(rng.uniform(10, 45)) * np.array([math.cos(axis), math.sin(axis), 0.0])
        roll = np.array([0.0, 0.0, math.radians(rng.uniform(-30, 30))])
        R = np.asarray(cv2.Rodrigues(tilt)[0] @ cv2.Rodrigues(roll)[0], np.float64)
        t = ray / ray[2] * dist - R @ centre
        XL = outline @ R.T + t
        XR = XL @ rig.R.T + rig.T
        ok = True
        for cam, X in ((rig.left, XL), (rig.right, XR)):
            uv = cam.project(X)
            ok &= bool(np.all(X[:, 2] > 0.05) and np.all(np.isfinite(uv)) and np.all(uv >= 2)
                       and np.all(uv[:, 0] <= cam.width - 3) and np.all(uv[:, 1] <= cam.height - 3))
        if ok:
            out.append((R, t))
    raise RuntimeError(f"only {len(out)} of {views} board poses fit rig {rig.name}")


def _fill_rays(lens: rc.Lens) -> None:
    """Put ``lens``'s sub-sample rays into the ray caster's cache, computed as its ``Lens.rays`` does (the same
    fixed-point inversion of plumb_bob) but stopped once converged (1e-12) instead of after 40 rounds, which
    makes a 640x480 lens about 4x cheaper. Same layout: (SUB * SUB, H * W, 3) float32 unit rays."""
    if lens in rc._RAYS:
        return
    h, w = lens.height, lens.width
    offs = (np.arange(rc.SUB) + 0.5) / rc.SUB - 0.5
    vv, uu = np.mgrid[0:h, 0:w].astype(np.float64)
    k1, k2, p1, p2, k3 = lens.dist
    out = []
    for oy in offs:
        for ox in offs:
            xd, yd = ((uu + ox).ravel() - lens.cx) / lens.fx, ((vv + oy).ravel() - lens.cy) / lens.fy
            a, b = xd.copy(), yd.copy()
            for _ in range(60):
                r2 = a * a + b * b
                rad = 1 + k1 * r2 + k2 * r2**2 + k3 * r2**3
                na = (xd - 2 * p1 * a * b - p2 * (r2 + 2 * a * a)) / rad
                nb = (yd - p1 * (r2 + 2 * b * b) - 2 * p2 * a * b) / rad
                step = max(float(np.abs(na - a).max()), float(np.abs(nb - b).max()))
                a, b = na, nb
                if step < 1e-12:
                    break
            d = np.column_stack([a, b, np.ones_like(a)])
            out.append((d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32))
    if len(rc._RAYS) > 1:
        rc._RAYS.clear()
    rc._RAYS[lens] = np.stack(out)


def render_rig(seed: int, folder: Path, *, views: int = 20, size: tuple[int, int] = (640, 480)) -> ImageRig:
    """Render ``views`` pairs of a random rig into ``folder/left/NN.png`` and ``folder/right/NN.png``."""
    truth, rig = make_image_rig(seed, size)
    rng = np.random.default_rng(seed + 7)
    (folder / "left").mkdir(parents=True, exist_ok=True)
    (folder / "right").mkdir(parents=True, exist_ok=True)
    for lens in (rig.left, rig.right):
        _fill_rays(lens)
    poses = _poses(rig, views, seed)
    pts = rig.target.points
    corners = tuple((rig.left.project(pts @ Rb.T + tb), rig.right.project(pts @ (rig.R @ Rb).T + rig.R @ tb + rig.T))
                    for Rb, tb in poses)
    for k, (Rb, tb) in enumerate(poses):
        for side, lens, (Rs, ts) in (("left", rig.left, (Rb, tb)),
                                     ("right", rig.right, (rig.R @ Rb, rig.R @ tb + rig.T))):
            img = rc.render(lens, rig.target, Rs, ts, seed=seed * 1000 + 2 * k + (side == "right"),
                            noise=float(rng.uniform(1.0, 2.0)))
            sigma = float(rng.uniform(0.3, 0.7))
            img = cv2.GaussianBlur(img, (0, 0), sigma)
            cv2.imwrite(str(folder / side / f"{k:02d}.png"), img)
    return replace(truth, corners=corners)


def errors(truth: ImageRig, cams: list[tuple[float, float, float, float]], baseline_m: float) -> dict[str, list[float]]:
    """Focal errors (% of f; fx fy of both cameras), principal point errors (px; cx cy), baseline error (%)."""
    ref = [(truth.left.fx, truth.left.fy, truth.left.cx, truth.left.cy),
           (truth.right.fx, truth.right.fy, truth.right.cx, truth.right.cy)]
    return {"f": [100 * abs(c[k] - t[k]) / t[k] for c, t in zip(cams, ref, strict=True) for k in (0, 1)],
            "c": [abs(c[k] - t[k]) for c, t in zip(cams, ref, strict=True) for k in (2, 3)],
            "b": [100 * abs(baseline_m - truth.baseline_m) / truth.baseline_m]}


def sigma_ratios(truth: ImageRig, cams: list[tuple[float, float, float, float]],
                 stds: list[tuple[float | None, ...]], baseline_m: float, baseline_std: float | None) -> list[float]:
    """|error| / reported sigma of fx fy cx cy of both cameras and the baseline (inf when no sigma)."""
    ref = [(truth.left.fx, truth.left.fy, truth.left.cx, truth.left.cy),
           (truth.right.fx, truth.right.fy, truth.right.cx, truth.right.cy)]
    out = [abs(c[k] - t[k]) / s[k] if s[k] else math.inf  # type: ignore[operator]
           for c, t, s in zip(cams, ref, stds, strict=True) for k in range(4)]
    out.append(abs(baseline_m - truth.baseline_m) / baseline_std if baseline_std else math.inf)
    return out
