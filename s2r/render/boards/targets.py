"""File-described targets for the renderer: ChArUco and Kalibr AprilGrid textures, and views cut by the edge.

Textures (grey, as RGB uint8) are drawn by OpenCV: ChArUco by ``cv2.aruco.CharucoBoard.generateImage`` with a
white margin of one square; Kalibr's AprilGrid as ``kalibr_create_target_pdf`` lays it out: tag36h11 markers
from ``cv2.aruco.generateImageMarker`` with a 2-bit black border, turned 180 degrees, tag 0 at the bottom left,
and black squares of the gap size at every tag corner; a Kalibr checkerboard is s2r's chessboard texture.

Rendering and pose sampling work in the *grid frame* of :class:`~s2r.render.boards.poses.BoardGeometry` (origin at the
first corner of an equivalent corner grid, x right, y down, z into the board); ``T_grid_target`` maps the
target's own frame (:mod:`s2r.targets`) into it, so the recorded truth is ``T_left_target = T_left_grid @
T_grid_target``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.lens.distortion import project_points
from s2r.profile import StereoProfile
from s2r.render.boards.poses import BoardGeometry
from s2r.render.textures import DARK, LIGHT, checkerboard_texture
from s2r.targets import AnyTarget, AprilGridTarget, CharucoTarget, CheckerboardTarget

__all__ = ["TargetLayout", "cut_views", "target_layout"]

FloatArray = NDArray[np.float64]
#: Texels per ChArUco square / AprilGrid tag / chessboard square.
TEXELS = 120
#: Share of a cut view's corners that must stay inside each image (the rest is cut by the edge).
CUT_VISIBLE = (0.3, 0.8)
_EDGE_PX = 3.0
_CUT_DIRECTIONS = 16


@dataclass(frozen=True)
class TargetLayout:
    """A target ready to render: ``texture`` (H, W, 3) uint8, its extent ``(x0, y0, x1, y1)`` in the grid frame
    (metres, texel row 0 at y0), ``T_grid_target`` (4x4), and an equivalent chessboard ``geometry`` for the pose
    sampler (its extent covers the texture)."""

    texture: NDArray[np.uint8]
    extent_m: tuple[float, float, float, float]
    T_grid_target: FloatArray
    geometry: BoardGeometry

    def corners_grid(self, target: AnyTarget) -> FloatArray:
        """The target's corners (N, 3) in the grid frame, metres."""
        pts = target.object_points()
        return pts @ self.T_grid_target[:3, :3].T + self.T_grid_target[:3, 3]


def _grey(img: NDArray[np.uint8]) -> NDArray[np.uint8]:
    scaled = np.where(img > 127, LIGHT, DARK).astype(np.uint8) if img.dtype == np.uint8 else img
    return np.repeat(scaled[:, :, None], 3, axis=2)


def _charuco(t: CharucoTarget) -> TargetLayout:
    d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, t.dictionary))
    board = cv2.aruco.CharucoBoard((t.squaresX, t.squaresY), t.squareLength, t.markerLength, d)
    board.setLegacyPattern(t.legacyPattern)
    img = board.generateImage((t.squaresX * TEXELS, t.squaresY * TEXELS), marginSize=0, borderBits=1)
    tex = np.pad(np.asarray(img, np.uint8), TEXELS, constant_values=255)
    s = t.squareLength
    T = np.eye(4)
    T[:3, 3] = (-s, -s, 0.0)  # grid origin at the first inner corner
    geometry = BoardGeometry((t.squaresX - 1, t.squaresY - 1), s, 1.0)
    return TargetLayout(_grey(tex), (-2 * s, -2 * s, t.squaresX * s, t.squaresY * s), T, geometry)


def _aprilgrid(t: AprilGridTarget) -> TargetLayout:
    tag = TEXELS
    gap = round(t.tagSpacing * TEXELS)
    pitch = tag + gap
    margin = tag // 2
    h = t.tagRows * pitch + gap + 2 * margin
    w = t.tagCols * pitch + gap + 2 * margin
    tex = np.full((h, w), 255, np.uint8)
    d = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11)
    for ty in range(t.tagRows):
        for tx in range(t.tagCols):
            marker = cv2.aruco.generateImageMarker(d, t.codeOffset + ty * t.tagCols + tx, tag, borderBits=2)
            r0, c0 = margin + gap + (t.tagRows - 1 - ty) * pitch, margin + gap + tx * pitch  # tag 0 bottom left
            tex[r0:r0 + tag, c0:c0 + tag] = np.asarray(marker, np.uint8)[::-1, ::-1]  # printed turned 180 deg
            for dr, dc in ((-gap, -gap), (-gap, tag), (tag, tag), (tag, -gap)):
                tex[r0 + dr:r0 + dr + gap, c0 + dc:c0 + dc + gap] = 0
    texel = t.tagSize / TEXELS
    step = t.tagSize * (1 + gap / TEXELS)
    height = (t.tagRows - 1) * step + t.tagSize  # top corner row in Kalibr's frame (y up)
    T = np.diag([1.0, -1.0, -1.0, 1.0])
    T[1, 3] = height
    pad = (gap + margin) * texel
    width = (t.tagCols - 1) * step + t.tagSize
    # the pose sampler keeps its "squares" >= 12 px: a third of a tag keeps tags >= 36 px, which decode
    spacing = t.tagSize / 3.0
    grid = (int(np.ceil(width / spacing)) + 1, int(np.ceil(height / spacing)) + 1)
    geometry = BoardGeometry(grid, spacing, max(0.0, pad / spacing - 1.0))
    return TargetLayout(_grey(tex), (-pad, -pad, width + pad, height + pad), T, geometry)


def _checkerboard(t: CheckerboardTarget) -> TargetLayout:
    s = t.colSpacingMeters
    geometry = BoardGeometry(t.pattern, s, 1.0)
    tex = checkerboard_texture(t.pattern, texels_per_square=TEXELS // 2, border_squares=1.0)
    return TargetLayout(tex, geometry.extent_m, np.eye(4), geometry)


def target_layout(target: AnyTarget) -> TargetLayout:
    """The texture, grid-frame extent and frame change of ``target``."""
    if isinstance(target, CharucoTarget):
        return _charuco(target)
    if isinstance(target, AprilGridTarget):
        return _aprilgrid(target)
    return _checkerboard(target)


def _visible_share(profile: StereoProfile, corners: FloatArray, T: FloatArray) -> float:
    """Smallest share, over both cameras, of ``corners`` (grid frame) imaged inside the image."""
    share = 1.0
    for cam, R, t in ((profile.left, np.eye(3), np.zeros(3)), (profile.right, profile.R, profile.T)):
        X = corners @ (R @ T[:3, :3]).T + (R @ T[:3, 3] + t)
        if np.any(X[:, 2] <= 0):
            return 0.0
        uv = project_points(cam, X)
        inside = ((uv[:, 0] >= _EDGE_PX) & (uv[:, 0] <= cam.width_px - 1 - _EDGE_PX) & (uv[:, 1] >= _EDGE_PX)
                  & (uv[:, 1] <= cam.height_px - 1 - _EDGE_PX))
        share = min(share, float(inside.mean()))
    return share


def _cut(profile: StereoProfile, corners: FloatArray, T: FloatArray, rng: np.random.Generator) -> FloatArray:
    """``T`` moved sideways until 30-80 % of the corners stay in both images (directions tried at random);
    ``T`` itself when no direction gets there."""
    size = float(np.ptp(corners[:, 0]) + np.ptp(corners[:, 1]))
    for _ in range(_CUT_DIRECTIONS):
        angle = rng.uniform(0.0, 2.0 * np.pi)
        direction = np.array([np.cos(angle), np.sin(angle), 0.0])
        for step in np.linspace(0.02, 1.2, 60) * size:
            moved = T.copy()
            moved[:3, 3] = T[:3, 3] + step * direction
            s = _visible_share(profile, corners, moved)
            if CUT_VISIBLE[0] <= s <= CUT_VISIBLE[1]:
                return moved
            if s < CUT_VISIBLE[0]:
                break
    return T


def cut_views(profile: StereoProfile, poses: list[FloatArray], corners: FloatArray, *, share: float,
              seed: int) -> tuple[list[FloatArray], list[bool]]:
    """Move about ``share`` of the views sideways (in the left camera's image plane, away from the image centre)
    until only 30-80 % of the corners stay inside both images; returns the poses and which were cut."""
    rng = np.random.default_rng([seed, 2])
    n_cut = round(share * len(poses))
    chosen = set(np.linspace(0, len(poses) - 1, n_cut).round().astype(int).tolist()) if n_cut else set()
    out, cut = [], []
    for k, T in enumerate(poses):
        if k not in chosen:
            out.append(T)
            cut.append(False)
            continue
        best = _cut(profile, corners, T, rng)
        out.append(best)
        cut.append(best is not T)
    return out, cut
