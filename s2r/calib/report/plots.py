"""Figures of the calibration report: coverage footprints, per-corner residual vectors, board poses in 3D,
and a thumbnail strip of every view with its error. Each returns a PNG data URI.

Frames: pixels (x right, y down) for image plots; the left camera's optical frame (metres: x right, y
down, z forward) for the 3D board poses.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import cv2
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import NDArray

from s2r.calib.detect.coverage import FOOTPRINT_CELL_PX, Coverage
from s2r.calib.solve.honesty.projection import ProjectionMap
from s2r.htmlreport import figure_to_data_uri, image_to_data_uri

__all__ = ["board_poses_3d", "coverage_maps", "projection_uncertainty", "residual_vectors", "thumbnail_strip"]

FloatArray = NDArray[np.float64]
_THUMB_W = 192


def coverage_maps(coverages: Mapping[str, Coverage], size: tuple[int, int]) -> str:
    """Per camera: how many views' boards cover each part of the image, axes in pixels."""
    w, h = size
    # constrained layout keeps each colour bar's label clear of the next plot's axis label
    fig, axes = plt.subplots(1, len(coverages), figsize=(5.2 * len(coverages), 3.8), squeeze=False,
                             layout="constrained")
    for ax, (label, cov) in zip(axes[0], coverages.items(), strict=True):
        data = cov.footprint if cov.footprint is not None else cov.counts
        extent = (0, w, h, 0) if cov.footprint is None else (0, data.shape[1] * FOOTPRINT_CELL_PX,
                                                              data.shape[0] * FOOTPRINT_CELL_PX, 0)
        im = ax.imshow(data, cmap="viridis", interpolation="nearest", extent=extent)
        ax.set_xlim(0, w)
        ax.set_ylim(h, 0)
        ax.set_title(f"{label}: boards cover {100 * cov.fraction:.0f} % of the image", fontsize=9)
        ax.set_xlabel("x (px)")
        ax.set_ylabel("y (px)")
        fig.colorbar(im, ax=ax, label="views covering" if cov.footprint is not None else "corners")
    return figure_to_data_uri(fig)


def projection_uncertainty(maps: Mapping[str, Mapping[str, ProjectionMap | None]], size: tuple[int, int]) -> str:
    """Per camera: the projection uncertainty (px, the larger of the covariance and jackknife maps) over the
    image at the maps' distance, with contours."""
    w, h = size
    fig, axes = plt.subplots(1, len(maps), figsize=(4.8 * len(maps), 3.6), squeeze=False)
    for ax, (label, pair) in zip(axes[0], maps.items(), strict=True):
        known = [m for m in pair.values() if m is not None]
        if not known:
            ax.set_axis_off()
            continue
        sigma = np.max([m.sigma for m in known], axis=0)
        first = known[0]
        im = ax.imshow(sigma, cmap="magma", extent=(0, w, h, 0), interpolation="bilinear")
        levels = [v for v in (0.05, 0.1, 0.2, 0.5, 1.0, 2.0) if float(sigma.min()) < v < float(sigma.max())]
        if levels:
            cs = ax.contour(first.xs, first.ys, sigma, levels=levels, colors="white", linewidths=0.7)
            ax.clabel(cs, fontsize=7, fmt="%g")
        ax.set_title(f"{label}: projection std at {first.distance_m:g} m, centre "
                     f"{max(m.centre_px for m in known):.2f} px", fontsize=9)
        ax.set_xlabel("x (px)")
        ax.set_ylabel("y (px)")
        fig.colorbar(im, ax=ax, label="px (worst direction)")
    return figure_to_data_uri(fig)


def residual_vectors(corners: Mapping[str, Sequence[NDArray[np.float32]]],
                     residuals: Mapping[str, Sequence[FloatArray]], size: tuple[int, int]) -> str:
    """Per camera: every used corner with its residual (projected minus detected) as an arrow, magnified."""
    w, h = size
    fig, axes = plt.subplots(1, len(corners), figsize=(5.6 * len(corners), 4.4), squeeze=False,
                             layout="constrained")
    for ax, label in zip(axes[0], corners, strict=True):
        pts = np.vstack([c.reshape(-1, 2) for c in corners[label]]).astype(np.float64)
        res = np.vstack([r.reshape(-1, 2) for r in residuals[label]])
        norm = np.linalg.norm(res, axis=1)
        scale = 0.04 * w / max(float(np.percentile(norm, 95)), 1e-6)  # the 95th percentile arrow: 4 % of the width
        arrows = ax.quiver(pts[:, 0], pts[:, 1], res[:, 0] * scale, res[:, 1] * scale, norm, angles="xy",
                           scale_units="xy", scale=1, cmap="plasma", width=0.003)
        key_px = _key_length(float(np.percentile(norm, 95)))
        ax.quiverkey(arrows, 0.82, 1.02, key_px * scale, f"{key_px:g} px residual", labelpos="W",
                     coordinates="axes", fontproperties={"size": 8})
        ax.set_xlim(0, w)
        ax.set_ylim(h, 0)
        ax.set_aspect("equal")
        rms = float(np.sqrt(np.mean(norm ** 2)))
        ax.set_title(f"{label}: residual arrows drawn {scale:.0f} times their length\nall corners incl. rejected: "
                     f"RMS {rms:.3f} px, max {float(norm.max()):.2f} px", fontsize=9, loc="left")
        ax.set_xlabel("x (px)")
        ax.set_ylabel("y (px)")
    return figure_to_data_uri(fig)


def _key_length(p95_px: float) -> float:
    """A round residual length (pixels) near ``p95_px`` for the arrow key: 0.05, 0.1, 0.2, 0.5, 1, 2, ..."""
    candidates = [m * 10.0 ** e for e in range(-3, 3) for m in (1.0, 2.0, 5.0)]
    return min(candidates, key=lambda c: abs(np.log(c / max(p95_px, 1e-6))))


def board_poses_3d(rvecs: Sequence[FloatArray], tvecs: Sequence[FloatArray], obj: NDArray[np.float32],
                   R: FloatArray, T: FloatArray) -> str:
    """The board outline of every used view and both cameras, in the left camera frame (metres)."""
    fig = plt.figure(figsize=(6.0, 4.8))
    ax = fig.add_subplot(projection="3d")
    pts = obj.reshape(-1, 3).astype(np.float64)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    outline = np.array([[lo[0], lo[1], 0], [hi[0], lo[1], 0], [hi[0], hi[1], 0], [lo[0], hi[1], 0],
                        [lo[0], lo[1], 0]])
    for rv, tv in zip(rvecs, tvecs, strict=True):
        Rb = cv2.Rodrigues(np.asarray(rv, np.float64).reshape(3, 1))[0]
        q = outline @ Rb.T + np.asarray(tv, np.float64).reshape(3)
        ax.plot(q[:, 0], q[:, 2], -q[:, 1], color="tab:blue", linewidth=0.8)
    right = -R.T @ T
    for c, label, colour in ((np.zeros(3), "left", "tab:green"), (right, "right", "tab:red")):
        ax.scatter([c[0]], [c[2]], [-c[1]], color=colour, s=30)
        ax.text(c[0], c[2], -c[1], f" {label}", fontsize=8)
    ax.set_xlabel("x right (m)")
    ax.set_ylabel("z forward (m)")
    ax.set_zlabel("up = -y (m)")
    ax.set_title("board poses in the left camera frame", fontsize=9)
    return figure_to_data_uri(fig)


def _thumb(path: Path | None, corners: NDArray[np.float32], size: tuple[int, int]) -> NDArray[np.uint8]:
    img = None if path is None else cv2.imread(str(path), cv2.IMREAD_COLOR)
    if img is None:  # no image at hand (bags): the corners on grey
        img = np.full((size[1], size[0], 3), 200, np.uint8)
    pts = corners.reshape(-1, 2)
    for x, y in pts:
        cv2.circle(img, (round(float(x)), round(float(y))), max(2, size[0] // 200), (0, 160, 0), -1)
    scale = _THUMB_W / img.shape[1]
    return np.asarray(cv2.resize(img, (_THUMB_W, round(img.shape[0] * scale)), interpolation=cv2.INTER_AREA),
                      np.uint8)


def thumbnail_strip(views: Sequence[tuple[str, NDArray[np.float32] | None, str, bool]],
                    paths: Mapping[str, tuple[Path, Path]], size: tuple[int, int], *, per_row: int = 6) -> str:
    """Every view's left image (detected corners in green) with its name and error; dropped views framed red.

    ``views``: (name, left corners or None, caption, used)."""
    tiles = []
    for name, corners, caption, used in views:
        path = paths.get(name, (None, None))[0]
        tile = _thumb(path, corners if corners is not None else np.zeros((0, 2), np.float32), size)
        band = np.full((34, tile.shape[1], 3), 255, np.uint8)
        cv2.putText(band, name[:24], (4, 13), cv2.FONT_HERSHEY_SIMPLEX, 0.4, (0, 0, 0), 1, cv2.LINE_AA)
        cv2.putText(band, caption[:30], (4, 28), cv2.FONT_HERSHEY_SIMPLEX, 0.4,
                    (0, 0, 0) if used else (0, 0, 200), 1, cv2.LINE_AA)
        tile = np.vstack([tile, band])
        colour = (0, 160, 0) if used else (0, 0, 220)
        tiles.append(cv2.copyMakeBorder(tile, 3, 3, 3, 3, cv2.BORDER_CONSTANT, value=colour))
    th, tw = max(t.shape[0] for t in tiles), max(t.shape[1] for t in tiles)
    tiles = [cv2.copyMakeBorder(t, 0, th - t.shape[0], 0, tw - t.shape[1], cv2.BORDER_CONSTANT,
                                value=(255, 255, 255)) for t in tiles]
    blank = np.full((th, tw, 3), 255, np.uint8)
    rows = [np.hstack(tiles[i:i + per_row] + [blank] * (per_row - len(tiles[i:i + per_row])))
            for i in range(0, len(tiles), per_row)]
    return image_to_data_uri(np.vstack(rows))
