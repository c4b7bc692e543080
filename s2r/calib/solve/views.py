"""From detections to calibration views: pairing, order checks, input checks with one-line errors.

A *view* is one image pair (or one image, mono) whose board was found; everything else becomes a
:class:`~s2r.profile.DroppedView` naming the file and why it was skipped.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.calib.detect import Detection
from s2r.errors import CalibrationError
from s2r.profile import DroppedView

__all__ = [
    "MAX_SOLVE_VIEWS",
    "MIN_VIEWS",
    "REPEAT_PX",
    "StereoViews",
    "check_sizes",
    "match_corner_order",
    "merge_repeats",
    "no_board_error",
    "repeat_distance",
    "repeat_of",
    "select_diverse",
    "stereo_views",
    "too_few_error",
]

#: Fewest usable views (pairs, or images for mono) a calibration accepts.
MIN_VIEWS = 5
#: Most views handed to OpenCV's solvers: their dense Levenberg-Marquardt grows with the cube of the view
#: count (400 views: about 20 s per camera and 45 s for the pair, 80 views: 0.2 s). Beyond this, the most
#: diverse views are solved (as ROS camera_calibration keeps only sufficiently different samples).
MAX_SOLVE_VIEWS = 120
Corners = NDArray[np.float32]


def _axes(corners: Corners, pattern: tuple[int, int]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Unit mean row direction (first to last column) and column direction (first to last row) of a grid."""
    cols, rows = pattern
    g = corners.reshape(rows, cols, 2).astype(np.float64)
    row_dir = np.mean(g[:, -1] - g[:, 0], axis=0)
    col_dir = np.mean(g[-1, :] - g[0, :], axis=0)
    return row_dir / (np.linalg.norm(row_dir) + 1e-12), col_dir / (np.linalg.norm(col_dir) + 1e-12)


def _candidates(corners: Corners, pattern: tuple[int, int]) -> list[Corners]:
    """The right grid's possible orderings: as found, reversed (180 deg), and for square grids 90 deg turns."""
    cols, rows = pattern
    out = [corners, corners[::-1].copy()]
    if cols == rows:
        g = corners.reshape(rows, cols, 2)
        out += [np.rot90(g, k).reshape(-1, 2).copy() for k in (1, 3)]
    return out


def match_corner_order(left: Corners, right: Corners, pattern: tuple[int, int]) -> tuple[Corners, bool]:
    """Reorder ``right`` so its corner k is the same board corner as ``left``'s corner k.

    Compares the whole grids' mean row and column directions (robust to a few noisy corners), which
    agree between the two cameras of a stereo pair; returns ``(right corners, reordered?)``.
    """
    lr, lc = _axes(left, pattern)
    best, best_score = right, -np.inf
    for cand in _candidates(right, pattern):
        rr, rc = _axes(cand, pattern)
        score = float(lr @ rr + lc @ rc)
        if score > best_score:
            best, best_score = cand, score
    return best, best is not right


def _label(det: Detection) -> str:
    return det.name


def check_sizes(detections: Sequence[Detection]) -> tuple[int, int]:
    """The one image size (w, h) of all readable images; CalibrationError naming two files otherwise."""
    first: Detection | None = None
    for det in detections:
        if det.size is None:
            continue
        if first is None:
            first = det
        elif det.size != first.size:
            raise CalibrationError(
                f"images differ in size: {first.name} is {first.size[0]}x{first.size[1]} "  # type: ignore[index]
                f"but {det.name} is {det.size[0]}x{det.size[1]}", path=det.name,
                hint="calibrate images of one resolution at a time")
    if first is None or first.size is None:
        raise CalibrationError("none of the images could be read", hint="check the files are PNG/JPEG images")
    return first.size


@dataclass(frozen=True)
class StereoViews:
    """Usable pairs: names, corners (N, 2) px per side, and every skipped image with its reason."""

    names: tuple[str, ...]
    left: tuple[Corners, ...]
    right: tuple[Corners, ...]
    reordered: tuple[str, ...]
    dropped: tuple[DroppedView, ...]


def _skip_reason(det: Detection) -> DroppedView:
    return DroppedView(name=_label(det), reason=f"{det.status.replace('_', ' ')}: {det.detail}")


def stereo_views(pairs: Sequence[tuple[str, Detection, Detection]], pattern: tuple[int, int]) -> StereoViews:
    """Keep the pairs whose board was found in both images, with the right corners in the left's order."""
    names: list[str] = []
    left: list[Corners] = []
    right: list[Corners] = []
    reordered: list[str] = []
    dropped: list[DroppedView] = []
    for name, dl, dr in pairs:
        bad = [d for d in (dl, dr) if d.status != "ok"]
        if len(bad) == 1:
            other = dr if bad[0] is dl else dl
            why = _skip_reason(bad[0])
            dropped.append(why.model_copy(update={"reason": f"{why.reason}; its partner {other.name} shows the "
                                                            "board, so the pair is dropped"}))
            continue
        if bad:
            dropped.extend(_skip_reason(d) for d in bad)
            continue
        assert dl.corners is not None and dr.corners is not None
        fixed, flipped = match_corner_order(dl.corners, dr.corners, pattern)
        if flipped:
            reordered.append(name)
        names.append(name)
        left.append(dl.corners)
        right.append(fixed)
    return StereoViews(tuple(names), tuple(left), tuple(right), tuple(reordered), tuple(dropped))


#: Views whose corners lie within this distance (px; the median over the corners, in both cameras) of an earlier
#: view's are repeats (a board held still while recording): merged into that view, so the std counts each board
#: pose once. The median, not the RMS: the detector misplaces the odd corner (two grey levels of noise moved one
#: corner of 7 in 98 still copies of a real set by 8-12 px, 1.0-1.8 px RMS), which must not hide a still board.
#: Sensor noise moves a still board's corners by 0.01-0.15 px; distinct views of seven real sets lie >= 1.1 px
#: apart.
REPEAT_PX = 0.2


def repeat_distance(a: NDArray[np.floating[Any]], b: NDArray[np.floating[Any]]) -> float:
    """Median distance (px) between the corresponding corners ((N, 2), same order) of two views."""
    d = np.asarray(a, np.float64).reshape(-1, 2) - np.asarray(b, np.float64).reshape(-1, 2)
    return float(np.median(np.sqrt(np.sum(d ** 2, axis=1))))


def merge_repeats(names: Sequence[str], left: Sequence[Corners], right: Sequence[Corners], *,
                  tol_px: float = REPEAT_PX) -> tuple[list[int], list[DroppedView]]:
    """Indices of the views to keep (the first of each group of near-identical views) and a DroppedView per
    repeat naming the view it repeats and the corner distance (px, :func:`repeat_distance`)."""
    keep: list[int] = []
    repeats: list[DroppedView] = []
    if not len(names):
        return keep, repeats
    pts_l = np.asarray([np.asarray(c, np.float64).reshape(-1, 2) for c in left])
    pts_r = np.asarray([np.asarray(c, np.float64).reshape(-1, 2) for c in right])
    for i in range(len(names)):
        if keep:
            dl = np.median(np.linalg.norm(pts_l[keep] - pts_l[i], axis=2), axis=1)
            dr = np.median(np.linalg.norm(pts_r[keep] - pts_r[i], axis=2), axis=1)
            worst = np.maximum(dl, dr)
            j = int(np.argmin(worst))
            if worst[j] < tol_px:
                repeats.append(repeat_of(names[i], names[keep[j]], float(worst[j])))
                continue
        keep.append(i)
    return keep, repeats


def repeat_of(name: str, earlier: str, distance_px: float) -> DroppedView:
    """The DroppedView of view ``name``, a repeat of view ``earlier`` (corners a median ``distance_px`` apart)."""
    return DroppedView(name=name, rms_px=distance_px, reason=(
        f"repeat of {earlier}: its corners lie a median {distance_px:.3f} px from that view's (a still board); "
        "merged into it so the std counts that board pose once"))


def no_board_error(n_images: int, pattern: tuple[int, int]) -> CalibrationError:
    """The error for 'no board anywhere', which is nearly always a wrong ``--pattern``."""
    cols, rows = pattern
    return CalibrationError(
        f"no {cols}x{rows} chessboard found in any of the {n_images} readable images", field="--pattern",
        hint=f"check --pattern: it counts INNER corners per row x column (a board of {cols + 1}x{rows + 1} "
             f"squares is {cols}x{rows}), and --square is the square size in metres")


def too_few_error(found: int, dropped: Sequence[DroppedView], *, what: str = "pairs",
                  pattern: tuple[int, int] | None = None) -> CalibrationError:
    """The error for fewer usable views than :data:`MIN_VIEWS`, saying why the others failed (and, when most
    images showed no board, that ``--pattern`` may be wrong)."""
    reasons: dict[str, int] = {}
    for d in dropped:
        key = d.reason.split(":")[0]
        reasons[key] = reasons.get(key, 0) + 1
    why = ", ".join(f"{n} {k}" for k, n in sorted(reasons.items())) or "no other images"
    hint = "record more views with the whole board visible in both cameras"
    if pattern is not None and 2 * reasons.get("no board", 0) > len(dropped):
        hint += (f"; if the board is in most images, check --pattern: it counts INNER corners "
                 f"(a board of {pattern[0] + 1}x{pattern[1] + 1} squares is {pattern[0]}x{pattern[1]})")
    noun = what if found != 1 else what.rstrip("s")
    return CalibrationError(f"only {found} usable {noun} found, at least {MIN_VIEWS} needed; skipped images: {why}",
                            hint=hint)


def _view_features(corners: Corners, pattern: tuple[int, int], size: tuple[int, int]) -> NDArray[np.float64]:
    """ROS-like view descriptor: board centre x, y (image fractions), sqrt of its area share, and skew."""
    cols, rows = pattern
    g = corners.reshape(rows, cols, 2).astype(np.float64)
    a, b, c, d = g[0, 0], g[0, -1], g[-1, -1], g[-1, 0]
    (ux, uy), (vx, vy) = c - a, d - b
    area = 0.5 * abs(float(ux * vy - uy * vx))  # quadrilateral area from its diagonals
    top, left = b - a, d - a
    cos = float(top @ left) / (float(np.linalg.norm(top) * np.linalg.norm(left)) + 1e-12)
    skew = abs(np.pi / 2 - float(np.arccos(np.clip(cos, -1.0, 1.0)))) / (np.pi / 2)
    centre = g.reshape(-1, 2).mean(axis=0)
    return np.array([centre[0] / size[0], centre[1] / size[1], np.sqrt(area / (size[0] * size[1])), skew])


def select_diverse(corners: Sequence[Corners], pattern: tuple[int, int], size: tuple[int, int], *,
                   max_views: int = MAX_SOLVE_VIEWS) -> list[int]:
    """Indices (sorted) of at most ``max_views`` views, chosen by farthest-point sampling of their
    position / size / skew descriptors so the kept views span what the set covers."""
    if len(corners) <= max_views:
        return list(range(len(corners)))
    feats = np.stack([_view_features(c, pattern, size) for c in corners])
    chosen = [int(np.argmin(np.linalg.norm(feats - feats.mean(axis=0), axis=1)))]
    dist = np.linalg.norm(feats - feats[chosen[0]], axis=1)
    while len(chosen) < max_views:
        nxt = int(np.argmax(dist))
        chosen.append(nxt)
        dist = np.minimum(dist, np.linalg.norm(feats - feats[nxt], axis=1))
    return sorted(chosen)
