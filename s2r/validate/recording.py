"""``validate SIM REAL --recording DIR``: the real camera measured on its own recording, the sim on the same boards.

1. Real: every stereo pair of DIR (``left/``+``right/`` or ``leftNN``/``rightNN``) goes through REAL's pipeline;
   Intel's metrics on each chessboard against its PnP plane (:mod:`s2r.quality`), and each board's pose.
2. Sim: the same board (pattern, square size) is rendered at each recovered pose, expressed in the left camera
   (``T_left_board = R1^T T_rect_board``, R1 the real rectification), through SIM; the renders go through SIM's
   pipeline with the same preset and the same metrics.
3. Per distance bin, sim and real side by side; a bin passes when Z accuracy and plane-fit RMS differ by at most
   ``depth_gap_pct`` points and fill rates by at most ``fill_gap``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.profile import StereoProfile
from s2r.progress import ProgressCallback
from s2r.quality.run import QualityResult, measure_board_views
from s2r.quality.summary import BinQuality
from s2r.validate.tolerances import Tolerances
from s2r.validate.verdict import Check

__all__ = ["RecordingComparison", "compare_recording", "recording_checks"]


@dataclass
class RecordingComparison:
    """Real and sim depth quality on the same boards, and the per-bin side-by-side rows."""

    folder: str
    pattern: tuple[int, int]
    square_m: float
    real: QualityResult
    sim: QualityResult
    rows: list[dict[str, Any]] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON: ``real`` and ``sim`` each with ``bins`` and ``frames``, plus ``rows``."""
        return {"folder": self.folder, "pattern": list(self.pattern), "square_m": self.square_m,
                "real": self.real.as_dict(), "sim": self.sim.as_dict(), "rows": self.rows}


def _left_poses(real: QualityResult, R1: NDArray[np.float64]) -> list[NDArray[np.float64] | None]:
    """Board poses in the real LEFT optical frame from poses in its rectified left frame."""
    rot = np.eye(4)
    rot[:3, :3] = R1.T
    return [None if T is None else rot @ T for T in real.poses]


def _sim_views(sim: StereoProfile, names: list[str], poses: list[NDArray[np.float64]], *, preset: str,
               pattern: tuple[int, int], square_m: float, seed: int, progress: ProgressCallback | None) -> Any:
    from s2r.depth.pipeline import StereoPipeline
    from s2r.quality.views import stereo_view
    from s2r.render.scenes import render_boards_at

    pairs = render_boards_at(sim, poses, pattern=pattern, square_m=square_m, seed=seed, jobs=1, progress=progress)
    pipeline = StereoPipeline(sim, preset=preset)
    return pipeline, [stereo_view(pipeline, n, left, right) for n, (left, right) in zip(names, pairs, strict=True)]


def compare_recording(sim: StereoProfile, real: StereoProfile, folder: str | Path, *, pattern: tuple[int, int],
                      square_m: float, preset: str, tol: Tolerances, seed: int = 0,
                      progress: ProgressCallback | None = None) -> RecordingComparison:
    """Measure REAL on the recording in ``folder`` and SIM on the same boards at the same poses (module docstring)."""
    from s2r.calib.detect.inputs import find_stereo_pairs
    from s2r.depth.pipeline import StereoPipeline
    from s2r.quality.inputs import FramePaths
    from s2r.quality.views import stereo_fb, stereo_views, stereo_visible_m

    pairs = find_stereo_pairs(Path(folder))
    frames = [FramePaths(a, right=b) for a, b in zip(pairs.left, pairs.right, strict=True)]
    real_pipe = StereoPipeline(real, preset=preset)
    real_q = measure_board_views(real, stereo_views(real_pipe, frames), pattern=pattern, square_m=square_m,
                                 fb_px_m=stereo_fb(real_pipe), source=f"real recording, preset {preset}",
                                 total=len(frames), visible_m=stereo_visible_m(real_pipe), progress=progress)
    posed = [(f.image, T) for f, T in zip(real_q.frames, _left_poses(real_q, real_pipe.rectification.R1),
                                          strict=True) if T is not None]
    sim_pipe, views = _sim_views(sim, [n for n, _ in posed], [T for _, T in posed], preset=preset, pattern=pattern,
                                 square_m=square_m, seed=seed, progress=progress)
    sim_q = measure_board_views(sim, views, pattern=pattern, square_m=square_m, fb_px_m=stereo_fb(sim_pipe),
                                source=f"sim renders of the recovered poses, preset {preset}",
                                visible_m=stereo_visible_m(sim_pipe))
    comparison = RecordingComparison(str(folder), pattern, square_m, real_q, sim_q)
    comparison.rows = _rows(real_q.bins, sim_q.bins, tol)
    return comparison


_METRICS = ("z_accuracy_pct", "plane_fit_rms_pct", "subpixel_rms_px", "fill_rate_pct")


def _rows(real: list[BinQuality], sim: list[BinQuality], tol: Tolerances) -> list[dict[str, Any]]:
    sim_by = {(b.lo_m, b.hi_m): b for b in sim}
    rows = []
    for r in real:
        s = sim_by.get((r.lo_m, r.hi_m))
        row: dict[str, Any] = {"lo_m": r.lo_m, "hi_m": r.hi_m, "real_frames": r.frames,
                               "sim_frames": 0 if s is None else s.frames}
        for m in _METRICS:
            row[f"real_{m}"] = getattr(r, m)
            row[f"sim_{m}"] = None if s is None else getattr(s, m)
        row["verdicts"] = _verdicts(row, tol)
        row["passed"] = all(v["passed"] for v in row["verdicts"]) if row["verdicts"] else False
        rows.append(row)
    return rows


def _verdicts(row: dict[str, Any], tol: Tolerances) -> list[dict[str, Any]]:
    out = []
    limits = {"z_accuracy_pct": tol.depth_gap_pct, "plane_fit_rms_pct": tol.depth_gap_pct,
              "fill_rate_pct": 100.0 * tol.fill_gap}
    for m, limit in limits.items():
        real, sim = row[f"real_{m}"], row[f"sim_{m}"]
        if real is None or sim is None:
            out.append({"metric": m, "gap": None, "limit": limit, "passed": False})
            continue
        gap = float(sim - real)
        out.append({"metric": m, "gap": gap, "limit": limit, "passed": abs(gap) <= limit})
    return out


def recording_checks(comparison: RecordingComparison) -> list[Check]:
    """One check per bin and metric: sim minus real within its limit (missing sim figures fail)."""
    out = []
    for row in comparison.rows:
        name = f"{row['lo_m']:g}-{row['hi_m']:g} m"
        for v in row["verdicts"]:
            label = v["metric"].removesuffix("_pct").replace("_", " ")
            if v["gap"] is None:
                text = f"recording {name}: {label} missing on the {'sim' if row['sim_frames'] == 0 else 'real'} side"
                out.append(Check("recording", f"{label} gap {name}", "missing", v["limit"], "% points", False, text))
                continue
            real, sim = row[f"real_{v['metric']}"], row[f"sim_{v['metric']}"]
            text = (f"recording {name}: {label} sim {sim:.3g} vs real {real:.3g} % (gap {v['gap']:+.3g}, "
                    f"limit {v['limit']:g} points)")
            out.append(Check("recording", f"{label} gap {name}", v["gap"], v["limit"], "% points", v["passed"], text))
    return out
