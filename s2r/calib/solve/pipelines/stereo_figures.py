"""Pieces of the stereo calibration's figures: the board in words, repeated views merged, the warnings about
dropped views, the choice between the flat and the bent board, the reported std (the larger of covariance and
jackknife) and the projection uncertainty maps."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from s2r.calib.solve.honesty.heldout import BEND_SIGMAS, StereoHeldout
from s2r.calib.solve.honesty.projection import ProjectionMap, covariance_projection_map, projection_map
from s2r.calib.solve.honesty.verdict import NOT_CONVERGED
from s2r.calib.solve.solvers.pair import PairSolution
from s2r.calib.solve.views import REPEAT_PX, StereoViews, merge_repeats
from s2r.profile import DroppedView

__all__ = ["board_text", "choose_warp", "dropped_warning", "fit_warnings", "merge_repeated_views", "projection_maps",
           "repeat_warning", "with_reported_std"]


def _nan_none(v: float) -> float | None:
    return float(v) if np.isfinite(v) else None


def board_text(pattern: tuple[int, int], square_m: float) -> str:
    """The chessboard used, in words (the summary and the report state it: every length scales with it)."""
    return f"chessboard {pattern[0]}x{pattern[1]} inner corners, {square_m * 1000:g} mm squares"


def with_reported_std(sol: PairSolution, held: StereoHeldout | None) -> PairSolution:
    """``sol`` with each std of the resampled parameters replaced by the larger of covariance and jackknife."""
    if held is None:
        return sol
    left, right = sol.std_left.copy(), sol.std_right.copy()
    for i, name in enumerate(("fx", "fy", "cx", "cy")):
        for side, arr in (("left", left), ("right", right)):
            value = held.std(f"{side} {name}").reported
            if value is not None and np.isfinite(arr[i]):
                arr[i] = value
    b, r = held.std("baseline").reported, held.std("rotation").reported
    return replace(sol, std_left=left, std_right=right,
                   baseline_std_m=b if b is not None and np.isfinite(sol.baseline_std_m) else sol.baseline_std_m,
                   rotation_std_deg=r if r is not None and np.isfinite(sol.rotation_std_deg) else sol.rotation_std_deg)


def projection_maps(sol: PairSolution, held: StereoHeldout | None, size: tuple[int, int], free: Sequence[int]
                    ) -> dict[str, dict[str, ProjectionMap | None]]:
    """Per camera the projection uncertainty at 1 m from the covariance and from the jackknife folds."""
    out: dict[str, dict[str, ProjectionMap | None]] = {}
    for i, (side, K, D, cov) in enumerate((("left", sol.K1, sol.D1, sol.cov_left),
                                           ("right", sol.K2, sol.D2, sol.cov_right))):
        folds = [] if held is None or len(held.fold_intrinsics) <= i else list(held.fold_intrinsics[i])
        out[side] = {"covariance": None if cov is None else covariance_projection_map(K, D, size, cov, free),
                     "jackknife": projection_map(K, D, size, folds)}
    return out


def choose_warp(sol: PairSolution, held: StereoHeldout | None, warped: PairSolution | None,
                 held_w: StereoHeldout | None) -> tuple[PairSolution, StereoHeldout | None, dict[str, Any] | None]:
    """The flat-board or the bent-board solve, whichever has the lower stereo held-out error, and the bend's
    figures (mm, with ``decision`` in words). ``held_w`` None with a ``warped`` solve: the bend was within
    ``BEND_SIGMAS`` std of flat, so not tested. ``warped``'s views are positions in ``sol``'s kept views; the
    result indexes like ``sol``."""
    if warped is None or warped.warp_m is None:
        return sol, held, None
    used = held is not None and held_w is not None and held_w.heldout_px < held.heldout_px
    std = warped.warp_std_m if warped.warp_std_m is not None else np.full(2, np.nan)
    figures = {"used": used, "warp_mm": [float(v) * 1000 for v in warped.warp_m],
               "warp_std_mm": [_nan_none(float(v) * 1000) for v in std],
               "heldout_flat_px": None if held is None else held.heldout_px,
               "heldout_warped_px": None if held_w is None else held_w.heldout_px,
               "decision": _warp_decision(used, held, held_w)}
    if not used:
        return sol, held, figures
    m = sol.keep
    return replace(warped, keep=tuple(m[j] for j in warped.keep), mismatched=sol.mismatched,
                   outliers=sol.outliers + tuple((m[j], a, b, c, why) for j, a, b, c, why in warped.outliers),
                   rejected_corners=tuple((m[j], a, b) for j, a, b in warped.rejected_corners)), held_w, figures


def _warp_decision(used: bool, held: StereoHeldout | None, held_w: StereoHeldout | None) -> str:
    """Why the bent board is used or not, in words."""
    if held_w is None or held is None:
        return (f"not used: within {BEND_SIGMAS:g} std of a flat board on both axes (not tested on held-out "
                "pairs)") if held is not None else "not used: too few pairs for a held-out test"
    errors = f"stereo held-out error {held_w.heldout_px:.3f} px bent, {held.heldout_px:.3f} px flat"
    return f"used: it lowers the {errors}" if used else f"not used: it does not lower the {errors}"


def merge_repeated_views(views: StereoViews) -> tuple[StereoViews, list[DroppedView]]:
    """The views without repeats of an earlier view (a still board), and a DroppedView per repeat."""
    keep, repeats = merge_repeats(views.names, views.left, views.right)
    if not repeats:
        return views, []
    return replace(views, names=tuple(views.names[i] for i in keep), left=tuple(views.left[i] for i in keep),
                   right=tuple(views.right[i] for i in keep)), repeats


def fit_warnings(held: StereoHeldout | None, sol: PairSolution) -> list[str]:
    """The warnings of the solve's own figures: more held-out corners left out than detector blunders explain
    (:meth:`StereoHeldout.blunder_warning`), a joint solve stopped at its step limit still improving."""
    return [*([] if held is None else held.blunder_warning()), *([] if sol.converged else [NOT_CONVERGED])]


def repeat_warning(repeats: Sequence[DroppedView]) -> list[str]:
    if not repeats:
        return []
    return [f"{len(repeats)} view(s) repeat an earlier view (corners a median of less than {REPEAT_PX} px apart: a "
            "board held still); merged into it, so the std counts each board pose once"]


def dropped_warning(dropped: Sequence[DroppedView]) -> list[str]:
    """One line when views with a board were dropped (outliers, mismatched pairs, a board in one image only)."""
    valid = [d.name for d in dropped if d.reason.startswith(("outlier", "mismatched")) or "shows the board" in d.reason]
    if not valid:
        return []
    named = ", ".join(valid[:8]) + (" ..." if len(valid) > 8 else "")
    return [f"{len(valid)} view(s) with a board found were dropped: {named} (each reason is listed under dropped)"]
